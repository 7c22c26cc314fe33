// `flutterscan replay SESSION_DIR [--config FILE] [--json]` runs today's per-frame
// pipeline (session/frame_processing.hpp, the session's workers' own) over every
// frame a session folder kept (frames/fNNNNNNNN.png with its descriptor, read
// by the files: camera) and compares what it reads with what the session read
// then (the frame's line in session.jsonl): per frame, the codes that read
// then and no longer read, and the codes that read now and did not then (a
// changed value counts as both), with the labels judged NO-READ then and now.
// Exit 0, or 1 when something that read before no longer reads (or a frame
// no longer processes), naming the frames; bad input exits 2 naming the path.
//
// The session folder does not hold its config: processing comes from --config
// (the line's TOML, as given to `scan`) or the defaults, said in the output.
// Each frame's exposure event comes from its session.jsonl line and its code
// from its descriptor; the model the config rebuilds from them is checked
// against the descriptor (how the frame was captured): a difference is refused
// with the defaults (exit 2: give --config) and warned about with --config.

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <regex>
#include <sstream>

#include "app/cli_errors.hpp"
#include "app/commands.hpp"
#include "capture/files_camera.hpp"
#include "codes/code_report.hpp"
#include "imaging/capture_descriptor.hpp"
#include "imaging/deblur.hpp"
#include "session/frame_model.hpp"
#include "session/frame_processing.hpp"
#include "session/session_config.hpp"
#include "session/session_start.hpp"
#include "session/worker_pool.hpp"

namespace flutterscan::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct ReplayOptions {
  std::string folder;
  std::string config;
  bool json = false;
};

/// A code read on a frame: what session.jsonl's `decoded` entries hold (other fields ignored).
struct Read {
  std::string text;
  std::string format;
  std::optional<long> x, y;
};

/// What one frame read: its codes and the labels judged NO-READ.
struct FrameReads {
  std::vector<Read> reads;
  int no_read = 0;
};

/// A kept frame: the image, its descriptor and the session's line for it.
struct KeptFrame {
  std::string name;  ///< fNNNNNNNN
  fs::path image;
  std::uint64_t sequence = 0;
  json line;
};

/// One frame's comparison.
struct FrameReplay {
  const KeptFrame* kept = nullptr;
  FrameReads then, now;
  std::vector<Read> lost;    ///< read then, not now
  std::vector<Read> gained;  ///< read now, not then
  std::string error;         ///< the frame failed now
  json flags = json::array();
};

bool is_image(const fs::path& path) {
  const std::string ext = path.extension().string();
  return ext == ".png" || ext == ".tif" || ext == ".tiff";
}

/// The reads of a session.jsonl line (`decoded`, `labels_in_view`), read tolerantly:
/// entries without a text are skipped, unknown fields ignored.
FrameReads reads_of(const json& line) {
  FrameReads out;
  const json decoded = line.value("decoded", json::array());
  if (decoded.is_array())
    for (const json& d : decoded) {
      if (!d.is_object() || !d.contains("text") || !d["text"].is_string()) continue;
      Read r;
      r.text = d["text"].get<std::string>();
      if (d.contains("format") && d["format"].is_string())
        r.format = d["format"].get<std::string>();
      if (d.contains("x") && d["x"].is_number()) r.x = std::lround(d["x"].get<double>());
      if (d.contains("y") && d["y"].is_number()) r.y = std::lround(d["y"].get<double>());
      out.reads.push_back(std::move(r));
    }
  // Every code read is one sighting, every label without a code one NO-READ sighting.
  const json labels = line.value("labels_in_view", json());
  if (labels.is_number_integer())
    out.no_read = std::max(0, labels.get<int>() - static_cast<int>(out.reads.size()));
  return out;
}

json read_json(const Read& r) {
  json j = {{"text", r.text}, {"format", r.format}};
  if (r.x) j["x"] = *r.x;
  if (r.y) j["y"] = *r.y;
  return j;
}

std::string describe(const Read& r) {
  std::string s = r.text + " (" + (r.format.empty() ? "?" : r.format) + ")";
  if (r.x && r.y) s += " at x " + std::to_string(*r.x) + ", y " + std::to_string(*r.y);
  return s;
}

/// `a` minus `b` as multisets of (text, format).
std::vector<Read> missing_from(const std::vector<Read>& a, const std::vector<Read>& b) {
  std::vector<bool> used(b.size(), false);
  std::vector<Read> out;
  for (const Read& r : a) {
    bool found = false;
    for (std::size_t i = 0; i < b.size() && !found; ++i)
      if (!used[i] && b[i].text == r.text && b[i].format == r.format) used[i] = found = true;
    if (!found) out.push_back(r);
  }
  return out;
}

/// session.jsonl's frame lines by camera sequence (a line with files_saved wins).
std::map<std::uint64_t, json> frame_lines(const fs::path& log_path, int& unreadable) {
  std::ifstream in(log_path);
  if (!in) throw UsageError("cannot read '" + log_path.string() + "'");
  std::map<std::uint64_t, json> lines;
  std::string text;
  unreadable = 0;
  while (std::getline(in, text)) {
    if (text.empty()) continue;
    json line = json::parse(text, nullptr, false);
    if (line.is_discarded() || !line.is_object()) {
      ++unreadable;  // e.g. the last line of a session that was killed mid-write
      continue;
    }
    if (!line.contains("sequence") || !line["sequence"].is_number_unsigned()) continue;
    const auto sequence = line["sequence"].get<std::uint64_t>();
    auto it = lines.find(sequence);
    if (it == lines.end() || line.value("files_saved", false)) lines[sequence] = std::move(line);
  }
  return lines;
}

/// The kept frames of `folder` with their session.jsonl lines; bad input names what is missing.
std::vector<KeptFrame> kept_frames(const fs::path& folder, int& unreadable_lines) {
  std::error_code error;
  if (!fs::exists(folder, error))
    throw UsageError("replay: no session folder '" + folder.string() + "'");
  if (!fs::is_directory(folder, error))
    throw UsageError("replay: '" + folder.string() + "' is not a folder");
  const fs::path log_path = folder / "session.jsonl";
  if (!fs::is_regular_file(log_path, error))
    throw UsageError("replay: '" + log_path.string() + "' is missing: '" + folder.string() +
                     "' is not a session folder");
  const fs::path frames = folder / "frames";
  if (!fs::is_directory(frames, error))
    throw UsageError("replay: '" + frames.string() + "' is missing: the session kept no frames");
  static const std::regex kept_name("f[0-9]{1,18}\\.png");
  std::vector<KeptFrame> kept;
  for (const auto& entry : fs::directory_iterator(frames, error)) {
    const fs::path path = entry.path();
    if (!entry.is_regular_file() || !std::regex_match(path.filename().string(), kept_name))
      continue;
    fs::path descriptor = path;
    descriptor.replace_extension(".json");
    if (!fs::exists(descriptor))
      throw UsageError("replay: frame '" + path.string() + "' has no descriptor '" +
                       descriptor.string() + "'");
    KeptFrame k;
    k.name = path.stem().string();
    k.image = path;
    kept.push_back(std::move(k));
  }
  if (error) throw UsageError("replay: cannot list '" + frames.string() + "': " + error.message());
  if (kept.empty())
    throw UsageError("replay: '" + frames.string() +
                     "' holds no kept frame (fNNNNNNNN.png with its fNNNNNNNN.json)");
  std::sort(kept.begin(), kept.end(),
            [](const KeptFrame& a, const KeptFrame& b) { return a.image < b.image; });
  const auto lines = frame_lines(log_path, unreadable_lines);
  for (KeptFrame& k : kept) {
    k.sequence = std::stoull(k.name.substr(1));
    const auto it = lines.find(k.sequence);
    if (it == lines.end())
      throw UsageError("replay: frame '" + k.image.string() + "' (sequence " +
                       std::to_string(k.sequence) + ") has no line in '" + log_path.string() + "'");
    if (!it->second.contains("event") || !it->second["event"].is_object())
      throw UsageError("replay: the line of frame '" + k.image.string() + "' in '" +
                       log_path.string() + "' has no exposure event");
    k.line = it->second;
  }
  return kept;
}

/// The exposure event a session.jsonl line logged (log_head in frame_processing.cpp).
session::ExposureRecord event_of(const json& line, std::uint16_t slot_count) {
  const json& e = line["event"];
  session::ExposureRecord event;
  event.frame_counter = e.value("counter", std::uint32_t{0});
  event.start_us = e.value("start_us", std::uint64_t{0});
  event.encoder_delta = e.value("encoder_delta", std::int32_t{0});
  event.slot_time_us = e.value("slot_time_us", std::uint32_t{0});
  event.code_id = e.value("code_id", std::uint8_t{0});
  event.flags = e.value("flags", std::uint16_t{0});
  event.slot_count = slot_count;
  return event;
}

bool differs(double a, double b) {
  return std::abs(a - b) > 1e-6 * std::max(1.0, std::abs(b));
}

bool differs(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return true;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (differs(a[i], b[i])) return true;
  return false;
}

std::string list_text(const std::vector<double>& v) {
  std::ostringstream s;
  s.precision(6);
  for (std::size_t i = 0; i < v.size(); ++i) s << (i ? "," : "") << v[i];
  return s.str();
}

/// Where the model `config` rebuilds for a frame differs from the frame's
/// descriptor (how it was captured) and its logged blur: "field (config X, frame Y)".
std::vector<std::string> model_differences(const imaging::CaptureModel& rebuilt,
                                           const imaging::CaptureModel& captured,
                                           const json& line) {
  std::vector<std::string> out;
  auto number = [&](const char* field, double a, double b) {
    if (differs(a, b)) {
      std::ostringstream s;
      s.precision(8);
      s << field << " (config " << a << ", frame " << b << ")";
      out.push_back(s.str());
    }
  };
  if (rebuilt.direction != captured.direction)
    out.push_back(std::string("direction (config ") + imaging::direction_name(rebuilt.direction) +
                  ", frame " + imaging::direction_name(captured.direction) + ")");
  if (differs(rebuilt.crosstalk, captured.crosstalk))
    out.push_back("crosstalk (config " + list_text(rebuilt.crosstalk) + ", frame " +
                  list_text(captured.crosstalk) + ")");
  if (differs(rebuilt.led_electrons, captured.led_electrons))
    out.push_back("led_electrons_per_slot (config " + list_text(rebuilt.led_electrons) +
                  ", frame " + list_text(captured.led_electrons) + ")");
  number("read_noise_e", rebuilt.read_noise, captured.read_noise);
  number("full_well_e", rebuilt.full_well, captured.full_well);
  number("black_level_dn", rebuilt.black_level, captured.black_level);
  number("gain_e_per_dn", rebuilt.gain, captured.gain);
  number("bit_depth", rebuilt.bit_depth, captured.bit_depth);
  // The descriptor keeps the refined blur; the line keeps the encoder's (rounded to 0.01 px).
  if (line.contains("blur_px") && line["blur_px"].is_number() &&
      std::abs(rebuilt.blur_px - line["blur_px"].get<double>()) > 0.006) {
    std::ostringstream s;
    s.precision(8);
    s << "blur_px from the encoder (config " << rebuilt.blur_px << ", session "
      << line["blur_px"].get<double>() << ")";
    out.push_back(s.str());
  }
  return out;
}

/// The config: --config FILE or the defaults, checked.
session::SessionConfig replay_config(const ReplayOptions& o) {
  session::SessionConfig config;
  if (!o.config.empty()) {
    auto loaded = session::load_config(o.config);
    if (!loaded.ok()) throw UsageError("--config: " + loaded.error());
    config = loaded.value();
  }
  if (auto problem = session::check_config(config); !problem.empty())
    throw UsageError((o.config.empty() ? std::string("config") : "--config " + o.config) + ": " +
                     problem);
  return config;
}

struct Replay {
  std::vector<FrameReplay> frames;
  std::vector<std::string> notes;               ///< said once, before the frames
  std::vector<std::string> optics_differences;  ///< with --config: warned
  std::string session_methods;                  ///< the methods the session's lines name
  double seconds = 0;
};

Replay replay(const ReplayOptions& o, session::SessionConfig config,
              const std::vector<KeptFrame>& kept) {
  Replay out;
  const auto started = std::chrono::steady_clock::now();
  const auto flat = session::load_flat_field(config.optics);
  if (!flat.ok()) throw UsageError(flat.error());
  const imaging::FlatField* flat_field = flat.value() ? &*flat.value() : nullptr;

  const fs::path frames_dir = kept.front().image.parent_path();
  auto camera = capture::make_files_camera(frames_dir.string());
  if (auto problem = camera->open(); !problem.empty()) throw UsageError("replay: " + problem);
  if (auto problem = camera->start(); !problem.empty()) throw UsageError("replay: " + problem);
  // The files camera plays every image with a descriptor beside it, in name order.
  std::vector<fs::path> played;
  std::error_code listing;
  for (const auto& entry : fs::directory_iterator(frames_dir, listing)) {
    fs::path descriptor = entry.path();
    descriptor.replace_extension(".json");
    if (entry.is_regular_file() && is_image(entry.path()) && fs::exists(descriptor))
      played.push_back(entry.path());
  }
  std::sort(played.begin(), played.end());
  std::map<fs::path, const KeptFrame*> by_path;
  for (const KeptFrame& k : kept) by_path[k.image] = &k;

  // Offline, no line to keep up with: every window is decoded and every second
  // pass the cascade wants runs.
  if (config.processing.decode_ms < 0) config.processing.decode_ms = session::kMaxDecodeMs;
  if (config.processing.latency_ms < 0) config.processing.latency_ms = session::kMaxLatencyMs;
  if (config.processing.second_pass_ms < 0)
    config.processing.second_pass_ms = session::kMaxSecondPassMs;
  session::WorkerShared shared(config);
  std::optional<LedCode> config_code;
  if (config.controller.code != "auto") config_code = config.controller.parsed_code;
  bool planned = false;
  std::map<std::string, int> methods;
  for (const fs::path& path : played) {
    capture::Frame frame;
    std::string error;
    const auto wait = camera->next_frame(frame, std::chrono::milliseconds(0), error);
    if (wait == capture::FrameWait::kError) throw UsageError("replay: " + error);
    if (wait != capture::FrameWait::kFrame)
      throw RuntimeFailure("replay: the files camera ended before '" + path.string() + "'");
    const auto it = by_path.find(path);
    if (it == by_path.end()) continue;  // an image that is not a kept frame
    const KeptFrame& k = *it->second;
    const fs::path descriptor_path = fs::path(path).replace_extension(".json");
    auto captured = imaging::from_descriptor(json::parse(frame.descriptor_json));
    if (!captured.ok())
      throw UsageError("replay: descriptor '" + descriptor_path.string() +
                       "': " + captured.error());
    // The frame's code is the one its descriptor names (code "auto" chose it on the line).
    const LedCode& code = captured.value().code;
    if (config_code && !(*config_code == code) && out.notes.empty())
      out.notes.push_back("the frames' code " + codes::format_code(code) +
                          " (from their descriptors) replaces the config's controller.code");
    config.controller.parsed_code = code;
    session::FrameJob job;
    try {
      job.index = k.line.value("index", std::uint64_t{0});
      job.event = event_of(k.line, static_cast<std::uint16_t>(code.length()));
      job.residual_us = k.line.value("clock_residual_us", 0.0);
    } catch (const json::exception& e) {
      throw UsageError("replay: the line of frame '" + path.string() +
                       "' in session.jsonl: " + e.what());
    }
    if (k.line.contains("method") && k.line["method"].is_string())
      ++methods[k.line["method"].get<std::string>()];
    // The config must rebuild the model the frame was captured under.
    auto rebuilt = session::frame_model(job.event, code, config, frame.format);
    if (rebuilt.ok()) {
      const auto differences = model_differences(rebuilt.value(), captured.value(), k.line);
      if (!differences.empty()) {
        std::string text;
        for (const auto& d : differences) text += (text.empty() ? "" : "; ") + d;
        if (o.config.empty())
          throw UsageError("replay: frame '" + path.string() +
                           "' was captured under other optics than the defaults: " + text +
                           ". Give the session's config with --config FILE");
        if (out.optics_differences.empty())
          out.optics_differences.push_back("frame " + k.name + ": " + text);
      }
      if (!planned) {
        session::plan_row_ffts(frame.format, rebuilt.value().direction);
        planned = true;
      }
    }
    job.frame = std::move(frame);
    FrameReplay r;
    r.kept = &k;
    r.then = reads_of(k.line);
    const session::FrameOutcome outcome = session::process_frame(job, config, shared, flat_field);
    if (!outcome.processed)
      r.error = outcome.log.value("error", std::string("not processed"));
    else
      r.now = reads_of(outcome.log);
    r.flags = outcome.log.value("flags", json::array());
    r.lost = missing_from(r.then.reads, r.now.reads);
    r.gained = missing_from(r.now.reads, r.then.reads);
    out.frames.push_back(std::move(r));
  }
  for (const auto& [name, count] : methods)
    out.session_methods += (out.session_methods.empty() ? "" : ", ") + name;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return out;
}

bool regressed(const FrameReplay& r) {
  return !r.lost.empty() || !r.error.empty();
}

void print_text(const ReplayOptions& o, const session::SessionConfig& config, const Replay& rp,
                int unreadable_lines) {
  std::cout << "replay   " << o.folder << ": " << rp.frames.size() << " kept frame"
            << (rp.frames.size() == 1 ? "" : "s") << "\n";
  std::cout << "config   "
            << (o.config.empty() ? "the defaults (a session folder does not keep its config; "
                                   "give the line's with --config FILE)"
                                 : o.config)
            << "; method " << session::processing_method_name(config.processing);
  if (!rp.session_methods.empty()) std::cout << " (the session's: " << rp.session_methods << ")";
  std::cout << "\n";
  for (const auto& note : rp.notes) std::cout << "note     " << note << "\n";
  if (unreadable_lines > 0)
    std::cout << "note     " << unreadable_lines
              << " line(s) of session.jsonl did not parse and were skipped\n";
  for (const auto& d : rp.optics_differences)
    std::cerr << "flutterscan: replay: warning: the config's optics differ from how the frames "
                 "were captured ("
              << d << "); the replay uses the config's\n";
  for (const FrameReplay& r : rp.frames) {
    std::cout << r.kept->name << "  ";
    if (!r.error.empty()) {
      std::cout << r.then.reads.size() << " read then; fails now: " << r.error << "\n";
    } else {
      std::cout << r.then.reads.size() << " read then, " << r.now.reads.size() << " now; NO-READ "
                << r.then.no_read << " then, " << r.now.no_read << " now"
                << (r.lost.empty() && r.gained.empty() && r.then.no_read == r.now.no_read
                        ? ": unchanged"
                        : "");
      if (r.lost.empty() && r.gained.empty() && !r.now.reads.empty()) {
        std::string values;
        for (const Read& read : r.now.reads) values += (values.empty() ? "" : ", ") + read.text;
        std::cout << " (" << values << ")";
      }
      std::cout << "\n";
    }
    for (const Read& read : r.lost) std::cout << "  no longer reads  " << describe(read) << "\n";
    for (const Read& read : r.gained)
      std::cout << "  reads now        " << describe(read)
                << (r.then.no_read > 0 ? " (NO-READ then)" : "") << "\n";
  }
}

json replay_json(const ReplayOptions& o, const session::SessionConfig& config, const Replay& rp,
                 int unreadable_lines) {
  json frames = json::array();
  for (const FrameReplay& r : rp.frames) {
    auto reads = [](const std::vector<Read>& v) {
      json a = json::array();
      for (const Read& read : v) a.push_back(read_json(read));
      return a;
    };
    json f = {{"frame", r.kept->name},
              {"sequence", r.kept->sequence},
              {"then", {{"read", reads(r.then.reads)}, {"no_read", r.then.no_read}}},
              {"no_longer_reads", reads(r.lost)},
              {"reads_now", reads(r.gained)}};
    if (r.error.empty())
      f["now"] = {{"read", reads(r.now.reads)}, {"no_read", r.now.no_read}, {"flags", r.flags}};
    else
      f["now"] = {{"error", r.error}, {"flags", r.flags}};
    frames.push_back(std::move(f));
  }
  json j = {{"session", o.folder},
            {"config", o.config.empty() ? json() : json(o.config)},
            {"method", session::processing_method_name(config.processing)},
            {"notes", rp.notes},
            {"optics_differences", rp.optics_differences},
            {"unreadable_log_lines", unreadable_lines},
            {"frames", frames},
            {"seconds", std::round(rp.seconds * 100) / 100}};
  return j;
}

void run(const ReplayOptions& o) {
  int unreadable_lines = 0;
  const std::vector<KeptFrame> kept = kept_frames(o.folder, unreadable_lines);
  const session::SessionConfig config = replay_config(o);
  const Replay rp = replay(o, config, kept);

  std::size_t reads_then = 0, reads_now = 0, lost = 0, gained = 0;
  int no_read_then = 0, no_read_now = 0;
  std::vector<std::string> regressions, regressed_names;
  for (const FrameReplay& r : rp.frames) {
    reads_then += r.then.reads.size();
    reads_now += r.now.reads.size();
    lost += r.lost.size();
    gained += r.gained.size();
    no_read_then += r.then.no_read;
    no_read_now += r.now.no_read;
    if (!regressed(r)) continue;
    std::string what;
    for (const Read& read : r.lost) what += (what.empty() ? "" : ", ") + read.text;
    if (!r.error.empty()) what += (what.empty() ? "" : ", ") + std::string("fails now");
    regressions.push_back(r.kept->name + " (" + what + ")");
    regressed_names.push_back(r.kept->name);
  }
  const std::size_t again = reads_then - lost;
  if (o.json) {
    json j = replay_json(o, config, rp, unreadable_lines);
    j["total"] = {{"frames", rp.frames.size()}, {"reads_then", reads_then},
                  {"read_again", again},        {"no_longer_read", lost},
                  {"reads_now", gained},        {"no_read_then", no_read_then},
                  {"no_read_now", no_read_now}, {"regressed_frames", regressed_names}};
    std::cout << j.dump() << "\n";
  } else {
    print_text(o, config, rp, unreadable_lines);
    std::cout << "total    " << rp.frames.size() << " frames in "
              << std::round(rp.seconds * 10) / 10 << " s: " << again << " of " << reads_then
              << " reads read again, " << lost << " no longer read"
              << (regressions.empty() ? ""
                                      : " (in " + std::to_string(regressions.size()) +
                                            (regressions.size() == 1 ? " frame)" : " frames)"))
              << ", " << gained << " read now that did not; NO-READ labels " << no_read_then
              << " then, " << no_read_now << " now\n";
  }
  if (!regressions.empty()) {
    std::string names;
    for (const auto& r : regressions) names += (names.empty() ? "" : ", ") + r;
    throw RuntimeFailure("replay: " + std::to_string(regressions.size()) + " frame" +
                         (regressions.size() == 1 ? "" : "s") +
                         " no longer read what the session read: " + names);
  }
}

}  // namespace

void add_replay(CLI::App& app) {
  auto o = std::make_shared<ReplayOptions>();
  CLI::App* command = app.add_subcommand(
      "replay",
      "Run today's pipeline over the frames a session kept and compare with what it read then");
  command->add_option("session_dir", o->folder, "a session folder (session.jsonl, frames/)")
      ->required();
  command->add_option("--config", o->config,
                      "the line's session configuration (TOML, as given to scan); default: the "
                      "defaults (a session folder does not keep its config)");
  command->add_flag("--json", o->json, "print one JSON object (frames, changes, totals)");
  command->callback([o] { run(*o); });
}

}  // namespace flutterscan::app
