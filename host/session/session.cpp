#include "session/session.hpp"

#include <optional>
#include <thread>
#include <utility>

#include "capture/camera_source.hpp"
#include "imaging/capture_descriptor.hpp"
#include "imaging/motion_frame.hpp"
#include "session/capture_stage.hpp"
#include "session/frame_memory.hpp"
#include "session/light_probe.hpp"
#include "session/line_devices.hpp"
#include "session/live_view.hpp"
#include "session/matching_stage.hpp"
#include "session/mqtt_publisher.hpp"
#include "session/pipeline.hpp"
#include "session/results_server.hpp"
#include "session/results_stage.hpp"
#include "session/session_clock.hpp"
#include "session/session_folder.hpp"
#include "session/session_report.hpp"
#include "session/session_start.hpp"
#include "session/session_summary.hpp"
#include "session/worker_pool.hpp"

namespace flutterscan::session {

SessionOutcome run_session(SessionConfig config, const std::atomic<bool>& stop,
                           const SessionHooks& hooks) {
  keep_freed_frame_memory();
  SessionOutcome outcome;
  auto say = [&](const std::string& text) {
    if (hooks.message) hooks.message(text);
  };
  auto fail = [&](std::string error, bool bad_input) {
    outcome.error = std::move(error);
    outcome.bad_input = bad_input;
    return outcome;
  };

  // Inputs: the configuration, the flat field (light that varies across the
  // field of view, corrected per frame), the sim line.
  auto flat = check_session_inputs(config);
  if (!flat.ok()) return fail(flat.error(), true);
  const imaging::FlatField* flat_field = flat.value() ? &*flat.value() : nullptr;

  // One virtual controller for the light probe and the session.
  SessionHooks line_hooks = hooks;
  if (config.controller.spec == "sim" && !line_hooks.virtual_controller)
    line_hooks.virtual_controller = std::make_shared<device::VirtualController>();

  // Scheme auto: the light measured on the line picks the scheme (light_probe.hpp).
  std::optional<SchemeLight> scheme_light;
  if (config.controller.code == "auto") {
    auto light = choose_scheme(config, line_hooks.virtual_controller, say);
    if (!light.ok()) return fail(light.error().message, light.error().bad_input);
    scheme_light = light.value();
  }

  // The line: controller first (the camera may need it (sim), and it must be
  // ready before frames), then the camera.
  ControllerLink link;
  bool bad_input = false;
  if (auto problem = connect_controller(config, line_hooks, link, bad_input); !problem.empty())
    return fail(problem, bad_input);
  auto camera =
      open_camera(config.camera, link.virtual_controller.get(), outcome.error, outcome.bad_input);
  if (!camera) return outcome;
  for (const auto& warning : camera->warnings()) say("warning: " + warning);
  const capture::FrameFormat format = camera->format();
  if (!capture::keeps_channels_apart(format.pixel_format))
    say("warning: pixel format " + capture::pixel_format_name(format.pixel_format) +
        " mixes the camera channels: the joint deblur loses accuracy (use raw Bayer or RGB)");
  imaging::Direction direction = imaging::Direction::kPlusX;
  imaging::parse_direction(config.optics.direction, direction);
  plan_row_ffts(format, direction);
  warm_frame_memory(frames_in_flight_bytes(format, config.processing));

  // The outputs: the session folder, result lines (TCP, serial).
  SessionFolder folder;
  const std::string folder_path = session_folder_name(config.output);
  if (auto p = folder.open(folder_path, config.output.disk_budget_mb); !p.empty())
    return fail(p, false);
  outcome.folder = folder_path;
  ResultsServer server;
  if (auto p = open_result_outputs(config.results, server, hooks.listening); !p.empty())
    return fail(p, false);
  MqttPublisher mqtt;
  if (config.results.mqtt)
    if (auto p = mqtt.start(*config.results.mqtt, say); !p.empty()) return fail(p, false);

  // Armed, the camera streaming; exposure events come in on the controller's reader thread.
  EventInbox inbox;
  link.client->set_event_handler([&](const device::EventNotice& notice) { inbox.receive(notice); });
  if (auto r = link.client->arm(); !r.ok())
    return fail("controller: Arm: " + r.error().message, false);
  if (auto p = camera->start(); !p.empty()) {
    link.client->disarm();
    return fail(p, false);
  }

  // The pipeline (docs/session.md): capture -> matching -> bounded queue ->
  // worker pool -> results thread, in capture order.
  Pipeline pipeline(config.processing.queue_depth);
  const std::int64_t start_ns = now_ns();
  WorkerPool workers(pipeline, config, flat_field, camera->settings().frame_rate_hz.value_or(0),
                     camera->live());
  ResultsStage results(config, imaging::length_along_motion(direction, format.width, format.height),
                       start_ns, pipeline, folder, server, config.results.mqtt ? &mqtt : nullptr);
  if (hooks.live_view) {
    hooks.live_view->begin(folder_path,
                           live_line(config, camera->name(), link.description, scheme_light));
    results.show_on(*hooks.live_view);
  }
  std::thread results_thread([&] { results.run(hooks.progress); });
  MatchingStage matching(config.processing.match_tolerance_us, config.optics);
  const CaptureEnd capture_end =
      run_capture(*camera, inbox, matching, pipeline, config.processing, start_ns, stop,
                  [&](const nlohmann::json& line) { folder.log(line); });
  pipeline.jobs.close();
  workers.join();
  pipeline.outcomes.close();
  results_thread.join();

  // LEDs off before anything else can fail.
  const auto disarmed = link.client->disarm();
  if (!disarmed.ok()) say("warning: controller Disarm failed: " + disarmed.error().message);
  if (hooks.live_view) hooks.live_view->set_state(disarmed.ok() ? "disarmed" : "disarm failed");
  const capture::CameraCounters camera_counters = camera->counters();
  const double duration_s = ms_between(start_ns, now_ns()) * 1e-3;
  server.close();
  mqtt.stop();

  // The summary: summary.json, report.html.
  SessionCounts counts =
      count_session(pipeline, matching, inbox, camera_counters, capture_end, folder, server);
  counts.camera = camera->name();
  counts.controller = link.description;
  counts.scheme_light = scheme_light;
  counts.format = format;
  counts.duration_s = duration_s;
  outcome.summary = session_summary(config, counts, results.results());
  if (config.results.mqtt) outcome.summary["results"]["mqtt"] = mqtt.summary();
  folder.close();
  if (auto p = folder.write_file("summary.json", outcome.summary.dump(2) + "\n"); !p.empty())
    return fail(p, false);
  if (config.output.report)
    if (auto p = write_report(folder_path, report_inputs(outcome.summary, results.results(),
                                                         config.controller.parsed_code));
        !p.empty())
      return fail(p, false);
  if (!capture_end.error.empty()) outcome.error = capture_end.error;
  return outcome;
}

}  // namespace flutterscan::session
