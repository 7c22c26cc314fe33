// End-to-end sim sessions: every label's decoded value equals its ground
// truth at the nominal noise level; jitter and lost frames reported exactly;
// drops under overload counted at the one place; a sim ring longer than the
// controller's event queue loses no event; rotation within the disk budget;
// results over TCP read by a client.
#include "session/session.hpp"
#include "session/session_folder.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "session/test/session_test_support.hpp"

namespace flutterscan::session {
namespace {

namespace fs = std::filesystem;
using namespace testing;

SessionOutcome run(const SessionConfig& config, const SessionHooks& hooks = {}) {
  std::atomic<bool> stop{false};
  return run_session(config, stop, hooks);
}

TEST(SimSession, EveryLabelReadEqualsItsGroundTruthAtNominalNoise) {
  const ScratchFolder scratch("nominal");
  const fs::path& out = scratch.path();
  const SessionOutcome outcome = run(small_sim_config(out, 90));
  ASSERT_EQ(outcome.error, "");
  const auto& s = outcome.summary;
  ASSERT_TRUE(s.contains("ground_truth"));
  EXPECT_GE(s["ground_truth"]["labels_fully_in_view"].get<int>(), 10);
  EXPECT_EQ(s["ground_truth"]["missed"], nlohmann::json::array()) << s.dump(2);
  EXPECT_EQ(s["ground_truth"]["wrong_values"], nlohmann::json::array()) << s.dump(2);
  EXPECT_EQ(s["frames_captured"], 90);
  EXPECT_EQ(s["frames_processed"], 90);
  EXPECT_EQ(s["frames_dropped"], 0);
  EXPECT_EQ(s["frames_without_event"], 0);
  EXPECT_EQ(s["events_without_frame"], 0);
  EXPECT_NEAR(s["clock_drift_ppm"].get<double>(), 40.0, 1.0);  // the sim camera's clock
  // Motion refinement on by default: frames with a label refine the encoder's blur, which the
  // sim camera gives exactly, so the refined blur stays within a few hundredths of a pixel.
  const auto& motion = s["motion_refinement"];
  EXPECT_GT(motion["frames_refined"].get<int>(), 10) << motion.dump();
  EXPECT_GT(motion["frames_without_edges"].get<int>() + motion["frames_refined"].get<int>(), 0);
  EXPECT_LT(std::abs(motion["refined_minus_encoder_px_p50"].get<double>()), 0.05) << motion.dump();
  // The sim line runs at a constant speed: a speed change or wandering motion is the exception.
  EXPECT_LE(2 * motion["frames_speed_change"].get<int>(), motion["frames_refined"].get<int>())
      << motion.dump();
  EXPECT_LE(2 * motion["frames_wandering"].get<int>(), motion["frames_refined"].get<int>())
      << motion.dump();
  EXPECT_LT(std::abs(motion["refined_minus_encoder_px_p5"].get<double>()), 0.2) << motion.dump();
  EXPECT_LT(std::abs(motion["refined_minus_encoder_px_p95"].get<double>()), 0.2) << motion.dump();
  // Every object read, each as one object over several frames, with its read record.
  for (const auto& o : s["object_results"]) {
    EXPECT_EQ(o["status"], "READ") << o.dump();
    EXPECT_EQ(o.value("conflicting_values", nlohmann::json()).is_null(), true) << o.dump();
    EXPECT_EQ(o["time"].get<std::string>().size(), 24u) << o.dump();  // 2026-11-25T17:05:29.123Z
    EXPECT_TRUE(o["trigger"].contains("exposure_counter")) << o.dump();
    EXPECT_EQ(o["corners"].size(), 4u) << o.dump();
    EXPECT_GT(o["module_px"].get<double>(), 0) << o.dump();
    EXPECT_EQ(o["quality"]["indicative"], true) << o.dump();
    EXPECT_GT(o["decode_ms"].get<double>(), 0) << o.dump();
  }
  // The record against the sim's truth: every read of a label whole in the frame has its
  // corners within 2 px, its module size within 10% and the label's symbology identifier.
  const auto& record = s["ground_truth"]["read_record"];
  EXPECT_GE(record["reads_checked"].get<int>(), 20) << record.dump();
  EXPECT_EQ(record["corners_within_2px"], record["reads_checked"]) << record.dump();
  EXPECT_EQ(record["modules_within_10pct"], record["reads_checked"]) << record.dump();
  EXPECT_EQ(record["symbology_ids_matching"], record["reads_checked"]) << record.dump();
  // The folder: one log line per frame and one per object (its result, as
  // summary.json lists it), the first frames' files, summary, report.
  int bad = 0;
  const auto lines = read_jsonl(out / "session.jsonl", bad);
  EXPECT_EQ(bad, 0);
  EXPECT_EQ(frame_lines(lines).size(), 90u);
  EXPECT_EQ(nlohmann::json(object_lines(lines)), s["object_results"]);
  EXPECT_EQ(s["object_results_omitted"], 0);
  EXPECT_TRUE(fs::exists(out / "frames" / "f00000000.png"));
  EXPECT_TRUE(fs::exists(out / "frames" / "f00000000.json"));
  EXPECT_TRUE(fs::exists(out / "frames" / "f00000000.fused.png"));
  EXPECT_TRUE(fs::exists(out / "summary.json"));
  EXPECT_TRUE(fs::exists(out / "report.html"));
}

TEST(SimSession, JitterAndLostFramesAreReportedExactly) {
  const ScratchFolder scratch("jitter");
  const fs::path& out = scratch.path();
  SessionConfig config = small_sim_config(out, 80);
  config.camera.options.push_back({"jitter", "0.05"});
  config.camera.options.push_back({"drop_probability", "0.12"});
  config.camera.options.push_back({"seed", "7"});
  const SessionOutcome outcome = run(config);
  ASSERT_EQ(outcome.error, "");
  const auto& s = outcome.summary;
  const int lost = s["camera_frames_lost"];
  EXPECT_GT(lost, 0);
  // Each lost frame left its exposure event behind, and nothing else did.
  EXPECT_EQ(s["events_without_frame"], lost);
  EXPECT_EQ(s["frames_without_event"], 0);
  EXPECT_EQ(s["events_received"], 80);
  EXPECT_EQ(s["frames_captured"].get<int>() + lost, 80);
  int bad = 0;
  const auto lines = read_jsonl(out / "session.jsonl", bad);
  int orphan_lines = 0;
  for (const auto& l : lines) orphan_lines += l.contains("event_without_frame") ? 1 : 0;
  EXPECT_EQ(orphan_lines, lost);
  // Blur follows the jittered speed (from the encoder), so what is read is right. (A
  // label whose only good frame was lost may be missed: that is what drops cost.)
  EXPECT_EQ(s["ground_truth"]["wrong_values"], nlohmann::json::array()) << s.dump(2);
  EXPECT_GT(s["ground_truth"]["labels_read"].get<int>(), 8);
}

TEST(SimSession, OverloadDropsAtTheQueueAndCountsEveryDrop) {
  const ScratchFolder scratch("overload");
  const fs::path& out = scratch.path();
  SessionConfig config = small_sim_config(out, 40);
  config.camera.options.push_back({"ring_frames", "4"});        // frames arrive as fast as copied
  config.processing.method = imaging::Method::kTotalVariation;  // slow on purpose
  config.processing.workers = 1;
  config.processing.queue_depth = 1;
  config.output.report = false;
  const SessionOutcome outcome = run(config);
  ASSERT_EQ(outcome.error, "");
  const auto& s = outcome.summary;
  const int dropped = s["frames_dropped"];
  EXPECT_GT(dropped, 0);
  // Every frame processed, dropped, or (frames this fast can outrun the
  // controller's queue of 16 events on a busy machine) finished without its
  // exposure event: each counted, none lost.
  const int without_event = s["frames_without_event"];
  EXPECT_EQ(s["frames_processed"].get<int>() + dropped + without_event,
            s["frames_captured"].get<int>());
  int bad = 0;
  const auto lines = read_jsonl(out / "session.jsonl", bad);
  EXPECT_EQ(count_flag(lines, "dropped"), dropped);
  EXPECT_EQ(count_flag(lines, "no-event"), without_event);
  EXPECT_EQ(frame_lines(lines).size(), 40u);
  if (HasFailure()) {
    // What went otherwise than processed or dropped, for the record.
    for (const auto& l : frame_lines(lines))
      if (count_flag({l}, "dropped") == 0 && count_flag({l}, "no-event") == 0 &&
          !l.contains("latency_ms"))
        ADD_FAILURE() << l.dump();
    ADD_FAILURE() << s.dump();
  }
}

TEST(SimSession, ARingLongerThanTheControllersEventQueueLosesNoEventNorObject) {
  // The ring pre-renders 24 frames before the session starts; the controller
  // holds 16 exposure events, so the ring's frames are exposed as delivered.
  // The session sees what it sees with every frame rendered live.
  auto labels_read = [](bool ring) {
    const ScratchFolder scratch(ring ? "ring" : "ring_live");
    SessionConfig config = small_sim_config(scratch.path(), 24);
    if (ring) config.camera.options.push_back({"ring_frames", "24"});
    // Delivered at the camera's frame rate, as a camera delivers them. Unpaced,
    // a busy machine can starve the event reader while frames keep coming, and
    // the controller's queue of 16 overflows: the session counts such events
    // as lost, but that is not what this test is about.
    config.camera.options.push_back({"pace_realtime", "true"});
    config.processing.queue_depth = 24;  // none dropped
    // Every second pass the cascade wants, in both runs: what it reads must not
    // depend on how busy the machine was (the budget's credit is CPU time), nor
    // on each frame's deadline (wall time from its arrival).
    config.processing.second_pass_ms = kMaxSecondPassMs;
    config.processing.latency_ms = kMaxLatencyMs;
    config.output.report = false;
    const SessionOutcome outcome = run(config);
    EXPECT_EQ(outcome.error, "");
    const auto& s = outcome.summary;
    EXPECT_EQ(s["events_received"], 24);
    EXPECT_EQ(s["frames_without_event"], 0);
    EXPECT_EQ(s["frames_processed"], 24);
    EXPECT_GE(s["ground_truth"]["labels_fully_in_view"].get<int>(), 5) << s.dump(2);
    EXPECT_EQ(s["ground_truth"]["missed"], nlohmann::json::array()) << s.dump(2);
    std::vector<std::string> values;  // one object per label: each value once
    for (const auto& o : s["object_results"]) values.push_back(o.value("value", "NO-READ"));
    EXPECT_EQ(std::set<std::string>(values.begin(), values.end()).size(), values.size())
        << s.dump(2);
    EXPECT_GE(values.size(), s["ground_truth"]["labels_fully_in_view"].get<std::size_t>());
    return values;
  };
  EXPECT_EQ(labels_read(true), labels_read(false));
}

TEST(SimSession, FrameFilesRotateWithinTheDiskBudgetAndTheLogNever) {
  const ScratchFolder scratch("rotation");
  const fs::path& out = scratch.path();
  SessionConfig config = small_sim_config(out, 24);
  config.output.keep_first_frames = 24;  // every frame's files
  config.output.disk_budget_mb = 2.5;    // a raw 640x240 frame is ~0.6 MB
  config.output.report = false;
  const SessionOutcome outcome = run(config);
  ASSERT_EQ(outcome.error, "");
  const auto& summary = outcome.summary;
  const auto& rotation = summary["rotation"];
  // Every frame is accounted for: written (then kept or rotated out), or, when
  // the writer was behind (a busy machine), counted as not saved and logged so.
  const int not_saved = summary["frames_not_saved"].get<int>();
  EXPECT_GT(rotation["frames_rotated"].get<int>(), 0);
  EXPECT_EQ(rotation["frames_rotated"].get<int>() + rotation["frames_kept"].get<int>(),
            summary["frames_saved"].get<int>());
  EXPECT_EQ(summary["frames_saved"].get<int>() + not_saved, 24) << summary.dump(2);
  std::uintmax_t bytes = 0;
  int pngs = 0;
  for (const auto& entry : fs::directory_iterator(out / "frames")) {
    bytes += entry.file_size();
    pngs += entry.path().extension() == ".png" &&
            entry.path().string().find(".fused") == std::string::npos;
  }
  EXPECT_LE(bytes, static_cast<std::uintmax_t>(2.5 * 1024 * 1024));
  EXPECT_EQ(pngs, rotation["frames_kept"].get<int>());
  int bad = 0;
  const auto frames = frame_lines(read_jsonl(out / "session.jsonl", bad));
  ASSERT_EQ(frames.size(), 24u);
  int logged_not_saved = 0;
  std::int64_t last_saved = -1;
  for (const auto& f : frames) {
    ASSERT_TRUE(f.contains("files_saved")) << f.dump();  // every frame kept says how it went
    if (f["files_saved"].get<bool>())
      last_saved = std::max(last_saved, f["sequence"].get<std::int64_t>());
    else
      ++logged_not_saved;
  }
  EXPECT_EQ(logged_not_saved, not_saved);
  // The oldest went first: frame 0 (the writer's queue is empty then) is gone,
  // the last frame written is there.
  EXPECT_EQ(rotation["first_sequence_rotated"], 0);
  EXPECT_FALSE(fs::exists(out / "frames" / "f00000000.png"));
  ASSERT_GE(last_saved, 0);
  const std::string last_file = SessionFolder::frame_file(static_cast<std::uint64_t>(last_saved));
  EXPECT_TRUE(fs::exists(out / last_file)) << last_file;
}

/// Reads lines from a TCP connection until the server closes it.
std::vector<std::string> read_lines_until_closed(int fd) {
  std::string buffer;
  char chunk[4096];
  for (;;) {
    const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
    if (n <= 0) break;
    buffer.append(chunk, static_cast<std::size_t>(n));
  }
  std::vector<std::string> lines;
  std::size_t start = 0;
  for (std::size_t end; (end = buffer.find('\n', start)) != std::string::npos; start = end + 1)
    lines.push_back(buffer.substr(start, end - start));
  EXPECT_EQ(start, buffer.size()) << "a partial line at the end";
  return lines;
}

TEST(SimSession, ATcpClientReadsOneLinePerObject) {
  const ScratchFolder scratch("tcp");
  const fs::path& out = scratch.path();
  SessionConfig config = small_sim_config(out, 50);
  config.results.tcp_port = 0;
  config.output.report = false;
  int client = -1;
  std::thread reader;
  std::vector<std::string> received;
  SessionHooks hooks;
  hooks.listening = [&](int port) {
    client = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<std::uint16_t>(port));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(::connect(client, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
    reader = std::thread([&] { received = read_lines_until_closed(client); });
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // accepted before any result
  };
  const SessionOutcome outcome = run(config, hooks);
  ASSERT_EQ(outcome.error, "");
  ASSERT_TRUE(reader.joinable());
  reader.join();
  ::close(client);
  ASSERT_GE(received.size(), 2u);
  const auto greeting = nlohmann::json::parse(received[0]);
  EXPECT_EQ(greeting["protocol"], "flutterscan-results");
  EXPECT_EQ(greeting["version"], 2);
  const auto& objects = outcome.summary["object_results"];
  ASSERT_EQ(received.size() - 1, objects.size());
  for (std::size_t i = 1; i < received.size(); ++i) {
    const auto line = nlohmann::json::parse(received[i]);
    EXPECT_EQ(line, objects[i - 1]);
    // A version 1 client finds every field it knows, with its type.
    EXPECT_TRUE(line["object"].is_number_unsigned());
    EXPECT_TRUE(line["belt_px"].is_number());
    EXPECT_TRUE(line["first_frame"].is_number_unsigned() &&
                line["last_frame"].is_number_unsigned());
    EXPECT_TRUE(line["frames"].is_number_integer() && line["decoded_frames"].is_number_integer());
    EXPECT_TRUE(line["status"] == "READ" || line["status"] == "NO-READ");
    if (line["status"] == "READ") {
      EXPECT_TRUE(line["value"].is_string() && line["format"].is_string()) << line.dump();
    }
  }
}

TEST(SessionConfigFile, ReadsTheAnnotatedExampleAndNamesBadKeys) {
  const auto example = load_config(FLUTTERSCAN_SOURCE_DIR "/docs/session-example.toml");
  ASSERT_TRUE(example.ok()) << example.error();
  SessionConfig config = example.value();
  EXPECT_EQ(check_config(config), "");
  EXPECT_EQ(config.controller.parsed_code.length(), 52);

  const auto unknown = parse_config("[processing]\nworkers = 2\nspeed = 3\n", "line3.toml");
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().find("line3.toml:3"), std::string::npos) << unknown.error();
  EXPECT_NE(unknown.error().find("processing.speed"), std::string::npos) << unknown.error();

  const auto wrong_type = parse_config("[optics]\npx_per_count = \"half\"\n", "line3.toml");
  ASSERT_FALSE(wrong_type.ok());
  EXPECT_NE(wrong_type.error().find("optics.px_per_count must be a number"), std::string::npos)
      << wrong_type.error();

  SessionConfig bad;
  bad.controller.code = "1234";
  EXPECT_NE(check_config(bad).find("controller.code"), std::string::npos);
  SessionConfig strobe;  // a white strobe by the regime map's name
  strobe.controller.code = "snapshot-2";
  EXPECT_EQ(check_config(strobe), "");
  EXPECT_EQ(strobe.controller.parsed_code.mask(1), 7);
  EXPECT_EQ(strobe.controller.parsed_code.mask(2), 0);
  strobe.controller.code = "snapshot-60";
  EXPECT_NE(check_config(strobe).find("snapshot-1..52"), std::string::npos);
  // A crosstalk entry is 0 or measurable: 1e-300 would underflow in the deconvolutions.
  SessionConfig faint;
  ASSERT_EQ(faint.optics.crosstalk.size(), 9u);
  faint.optics.crosstalk[2] = 1e-300;
  EXPECT_NE(check_config(faint).find("optics.crosstalk[0][2]"), std::string::npos)
      << check_config(faint);
  faint.optics.crosstalk[2] = 0;
  EXPECT_EQ(check_config(faint), "");

  const auto no_rotate = parse_config("[processing]\ntry_rotate = false\n", "line3.toml");
  ASSERT_TRUE(no_rotate.ok()) << no_rotate.error();
  EXPECT_FALSE(no_rotate.value().processing.try_rotate);
  EXPECT_EQ(config.processing.decode_area, reader::DecodeArea::kLabels);  // the default
  const auto whole = parse_config("[processing]\ndecode_area = \"frame\"\n", "line3.toml");
  ASSERT_TRUE(whole.ok()) << whole.error();
  EXPECT_EQ(whole.value().processing.decode_area, reader::DecodeArea::kFrame);
  const auto bad_area = parse_config("[processing]\ndecode_area = \"roi\"\n", "line3.toml");
  ASSERT_FALSE(bad_area.ok());
  EXPECT_NE(bad_area.error().find("line3.toml"), std::string::npos) << bad_area.error();
  EXPECT_NE(bad_area.error().find("processing.decode_area 'roi'"), std::string::npos)
      << bad_area.error();
  EXPECT_TRUE(config.processing.try_rotate);  // the annotated example keeps it on

  // The second pass's tries, by name; an unknown one is refused by name with its line.
  EXPECT_EQ(config.processing.second_pass_tries, SecondPassTries{});
  const auto every_try = parse_config("[processing]\nsecond_pass_tries = \"all\"\n", "line3.toml");
  ASSERT_TRUE(every_try.ok()) << every_try.error();
  EXPECT_TRUE(every_try.value().processing.second_pass_tries.fit);
  EXPECT_TRUE(every_try.value().processing.second_pass_tries.tv_on_sums);
  const auto bad_try = parse_config(
      "[processing]\nworkers = 2\nsecond_pass_tries = \"bar-sums,guess\"\n", "line3.toml");
  ASSERT_FALSE(bad_try.ok());
  EXPECT_NE(bad_try.error().find("line3.toml:3"), std::string::npos) << bad_try.error();
  EXPECT_NE(bad_try.error().find("'guess' is not a second-pass try"), std::string::npos)
      << bad_try.error();
  const auto tries_type = parse_config("[processing]\nsecond_pass_tries = 3\n", "line3.toml");
  ASSERT_FALSE(tries_type.ok());
  EXPECT_NE(tries_type.error().find("processing.second_pass_tries"), std::string::npos)
      << tries_type.error();

  // The method: "cascade" (the example's and the default) or one method everywhere; the
  // cascade's budget "auto" or ms per frame within 0..1e6.
  EXPECT_TRUE(config.processing.cascade);
  EXPECT_EQ(config.processing.second_pass_ms, -1);
  const auto tv = parse_config("[processing]\nmethod = \"tv\"\n", "line3.toml");
  ASSERT_TRUE(tv.ok()) << tv.error();
  EXPECT_FALSE(tv.value().processing.cascade);
  EXPECT_EQ(tv.value().processing.method, imaging::Method::kTotalVariation);
  const auto bad_method = parse_config("[processing]\nmethod = \"fast\"\n", "line3.toml");
  ASSERT_FALSE(bad_method.ok());
  EXPECT_NE(bad_method.error().find("processing.method 'fast' is none of cascade"),
            std::string::npos)
      << bad_method.error();
  // A processing key taking "auto" (-1) or ms: each parsed into `field`, a
  // word refused naming the key on its line (after `blank_lines` blank lines).
  auto auto_or_ms = [](const std::string& key, double ProcessingConfig::*field, double ms,
                       int blank_lines) {
    const auto automatic = parse_config("[processing]\n" + key + " = \"auto\"\n", "line3.toml");
    ASSERT_TRUE(automatic.ok()) << automatic.error();
    EXPECT_EQ(automatic.value().processing.*field, -1) << key;
    const auto fixed = parse_config(
        "[processing]\n" + key + " = " + std::to_string(std::lround(ms)) + "\n", "line3.toml");
    ASSERT_TRUE(fixed.ok()) << fixed.error();
    EXPECT_EQ(fixed.value().processing.*field, ms) << key;
    const auto word =
        parse_config("[processing]\n" + std::string(static_cast<std::size_t>(blank_lines), '\n') +
                         key + " = \"soon\"\n",
                     "line3.toml");
    ASSERT_FALSE(word.ok()) << key;
    const std::string at = "line3.toml:" + std::to_string(2 + blank_lines) + ": processing." + key;
    EXPECT_NE(word.error().find(at), std::string::npos) << word.error();
  };
  auto_or_ms("second_pass_ms", &ProcessingConfig::second_pass_ms, 5, 0);
  SessionConfig negative;
  negative.processing.second_pass_ms = -5;
  EXPECT_NE(check_config(negative).find("processing.second_pass_ms"), std::string::npos);
  // The first pass's decode budget: "auto" (the default) or ms per frame within (0, 1e6].
  EXPECT_EQ(config.processing.decode_ms, -1);
  auto_or_ms("decode_ms", &ProcessingConfig::decode_ms, 12, 1);
  SessionConfig no_time;
  no_time.processing.decode_ms = 0;
  EXPECT_NE(check_config(no_time).find("processing.decode_ms"), std::string::npos);
  negative.processing.second_pass_ms = 2e6;
  EXPECT_NE(check_config(negative).find("processing.second_pass_ms"), std::string::npos);
  // Each frame's deadline after its arrival: none (the default), "auto" or ms within (0, 1e6].
  EXPECT_EQ(config.processing.latency_ms, kMaxLatencyMs);
  auto_or_ms("latency_ms", &ProcessingConfig::latency_ms, 80, 0);
  SessionConfig never;
  never.processing.latency_ms = 0;
  EXPECT_NE(check_config(never).find("processing.latency_ms"), std::string::npos);

  // Code "auto": optics.electrons is optional (the session measures the light).
  EXPECT_TRUE(config.optics.electrons_given);  // the example gives it
  const auto auto_light = parse_config(
      "[controller]\ncode = \"auto\"\nprobe_frames = 4\n[optics]\npaper_reflectance = 0.85\n",
      "line3.toml");
  ASSERT_TRUE(auto_light.ok()) << auto_light.error();
  SessionConfig measured = auto_light.value();
  EXPECT_FALSE(measured.optics.electrons_given);
  EXPECT_EQ(measured.optics.paper_reflectance, 0.85);
  EXPECT_EQ(measured.controller.probe_frames, 4);
  EXPECT_EQ(check_config(measured), "");
  measured.optics.paper_reflectance = 1.5;
  EXPECT_NE(check_config(measured).find("optics.paper_reflectance"), std::string::npos);
  measured.optics.paper_reflectance = 1;
  measured.controller.probe_frames = 0;
  EXPECT_NE(check_config(measured).find("controller.probe_frames"), std::string::npos);

  SessionConfig unknown_symbology;
  unknown_symbology.processing.symbologies = "Code128,Code129";
  EXPECT_NE(check_config(unknown_symbology).find("processing.symbologies"), std::string::npos);
}

}  // namespace
}  // namespace flutterscan::session
