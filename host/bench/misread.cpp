// Misreads (`make bench` part `misread`): every value the product reports on
// frames of real photos and of print with no code, counted right, wrong (a
// misread) or unexpected (a read where there is no code), per path, per
// second-pass try and per decoder, with 95% upper bounds on the rates.
//
//   misread_bench [--photos DIR]... [--electrons 300,1000,3000] [--seeds N]
//                 [--motions LIST] [--scenes colour,grey] [--turns DEG,...]
//                 [--paths LIST] [--tries LIST;LIST] [--every N] [--match TEXT]
//                 [--shard K/N] [--csv FILE] [--frames DIR]
//
// Positives: each photo with NAME.txt beside it (the text its code encodes);
// negatives: each photo with no .txt beside it, and rendered text (no code).
// Default folders ../shared/data/real-labels and ../shared/data/real-labels-2
// (from the repository root); without them the bench says so and exits 0.
// Each scene is captured as the real-print benchmark captures it (the session's
// default line: seed-maxmin-1, c = 3, crosstalk, read noise 4 e-, 12 bits, 52 px
// along +x), the scene moving by one of --motions:
//   continuous  the physics: moving continuously within each slot (the model's)
//   steps       in whole-pixel steps, still within each slot (a mismatch)
//   jitter      each slot's speed off by 5% rms (a belt's)
//   blur+4%     4% more motion than the encoder tells the session
//   crosstalk   the camera's LED-to-channel mixing a quarter stronger than the model's
// Paths: "session" is session::process_frame with the line's config, offline
// (every window the cascade wants gets its second pass); "session-30fps" and
// "session-60fps" the same with the credit two workers leave at that rate; "cascade" is what
// `flutterscan deblur --decode` runs (motion refined, joint Wiener, every paper
// run and code region read again by the second pass, the whole frame read).
// --tries names the second-pass tries each path runs, sets separated by ';'
// ("default": the product's; "all": every try).
//
// A value is right when it is the photo's text or a second code the reader
// reads on the sharp photo itself (an add-on, a neighbouring label); anything
// else on a positive is a misread, anything on a negative is unexpected.

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "bench/cpu_model.hpp"
#include "bench/real_print_photos.hpp"
#include "bench/real_print_session.hpp"
#include "imaging/deblur.hpp"
#include "imaging/exposure_timeline.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/motion_refinement.hpp"
#include "reader/barcode_reader.hpp"
#include "reader/code_reading.hpp"
#include "session/second_pass.hpp"
#include "sim/colour_scene.hpp"
#include "sim/forward_model.hpp"
#include "sim/photo_scene.hpp"
#include "sim/pixel_integration.hpp"
#include "sim/scene.hpp"
#include "sim/speed_profile.hpp"
#include "sim/timeline_forward.hpp"

namespace {

using namespace flutterscan;
namespace fs = std::filesystem;

constexpr double kBlurPx = 52;
constexpr int kSupersample = sim::kSimSupersample;
/// The mismatches' sizes: jitter per slot (rms), the blur told short, the crosstalk's excess.
constexpr double kJitterRms = 0.05, kBlurExcess = 0.04, kCrosstalkExcess = 0.25;

struct Options {
  std::vector<std::string> photos;
  std::vector<double> electrons = {300, 1000, 3000};
  int seeds = 1;
  std::vector<std::string> motions = {"continuous", "steps"};
  std::vector<std::string> scenes = {"colour", "grey"};
  std::vector<double> turns = {0};
  std::vector<std::string> paths = {"session", "cascade"};
  std::string tries = "default";
  int every = 1;
  std::string match;  ///< only subjects whose name contains this
  std::string shard = "0/1";
  std::string csv;
  std::string frames;  ///< a folder the frames are kept in and taken from (empty: none)
};

/// A scene to capture: a photo (with its text, or none) or rendered print.
struct Subject {
  std::string name;
  std::string text;  ///< empty: no code in it (a negative)
  sim::SceneSpec spec;
  bool photo = true;
  /// The decoders read its text on the photo file itself, backed or not (the ceiling).
  bool original_reads = false;
  std::set<std::string> seconds;  ///< other texts the decoders read on the photo file
};

/// One reported value.
struct Report {
  std::string subject, scene, motion, path, tries, text, format, decoder, pass, evidence, verdict;
  double electrons = 0, turn = 0;
  int seed = 0;
  bool held = false;  ///< logged as unconfirmed, not reported (read_evidence.hpp)
};

/// One frame read by one path.
struct FrameRun {
  std::string subject, scene, motion, path, tries;
  double electrons = 0;
  bool positive = true, read_right = false, ceiling = false;
  double ms = 0;
  int windows = 0;  ///< windows decoded (bench::SessionRead)
};

/// The photos of `dir`: with a .txt (positives) and without (negatives).
std::vector<Subject> photo_subjects(const std::string& dir) {
  std::vector<Subject> out;
  for (const fs::path file : bench::photo_files(dir)) {
    Subject s;
    s.name = fs::path(dir).filename().string() + "/" + file.stem().string();
    const fs::path txt = fs::path(file).replace_extension(".txt");
    if (fs::exists(txt)) {
      std::ifstream in(txt, std::ios::binary);
      s.text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    auto spec = bench::photo_scene_spec(file.string(), kBlurPx);
    if (!spec.ok()) {
      std::cerr << file << ": " << spec.error() << "\n";
      continue;
    }
    s.spec = spec.value();
    out.push_back(std::move(s));
  }
  return out;
}

/// Rendered print with no code in it: text of several sizes, on paper with texture.
std::vector<Subject> rendered_negatives() {
  const std::vector<std::string> texts = {"SHIP TO: 4410 RIVERSIDE DR 98052 REF 00713",
                                          "111 000 111 000 1111 0000 11 00 1",
                                          "LOT 2026-11-29 EXP 2027-05 BATCH 88213 QTY 24",
                                          "IIII lllll IIIII 11111 lllll IIII ||||| 1111"};
  std::vector<Subject> out;
  int n = 0;
  for (const std::string& text : texts)
    for (const double module : {1.5, 2.5, 3.5}) {
      Subject s;
      s.name = "rendered/text-" + std::to_string(++n);
      s.photo = false;
      s.spec.kind = sim::SceneKind::kText;
      s.spec.content = text;
      s.spec.module_px = module;
      s.spec.width = 1200;
      s.spec.height = 240;
      s.spec.texture = 0.05;
      s.spec.print_blur_px = 0.5;
      out.push_back(std::move(s));
    }
  return out;
}

/// The scene's reflectance under each LED, rendered kSupersample times finer.
Result<std::vector<imaging::Plane>, std::string> render_bands(const Subject& s, bool colour) {
  using Out = Result<std::vector<imaging::Plane>, std::string>;
  if (s.photo) {
    auto bands = sim::render_photo_bands(s.spec, kSupersample);
    if (!bands.ok() || colour) return bands;
    const imaging::Plane grey = sim::fuse_bands(bands.value());
    return Out::success({grey, grey, grey});
  }
  auto plane = sim::render_scene(s.spec, kSupersample);
  if (!plane.ok()) return Out::failure(plane.error());
  return Out::success({plane.value(), plane.value(), plane.value()});
}

/// The expected electrons of `bands` under `model` with the scene moving as `motion` says.
imaging::Image expected(const std::vector<imaging::Plane>& bands, imaging::CaptureModel model,
                        const std::string& motion, std::uint64_t seed) {
  const int slots = model.code.length();
  std::vector<imaging::ExposureSegment> segments;
  if (motion == "steps") {
    // Still within each slot, at its start rounded to the pixel.
    for (int t = 0; t < slots; ++t)
      segments.push_back({std::round(t * model.blur_px / slots), 0, model.code.mask(t), 1});
  } else if (motion == "jitter") {
    segments = imaging::segments_from_boundaries(
        model.code, sim::jittered_slot_boundaries(slots, model.blur_px, kJitterRms, seed));
  } else {
    if (motion == "blur+4%") model.blur_px *= 1 + kBlurExcess;
    if (motion == "crosstalk")
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k)
          if (c != k) model.crosstalk[static_cast<std::size_t>(c * 3 + k)] *= 1 + kCrosstalkExcess;
    segments = imaging::slot_segments(model);
  }
  return sim::expected_colour_electrons_timeline(bands, model, segments, kSupersample).value();
}

/// A frame kept as raw 16-bit samples: width, height and channels (int32) first.
void keep_frame(const fs::path& path, const imaging::Image& dn) {
  fs::create_directories(path.parent_path());
  const fs::path partial = fs::path(path).concat(".partial");
  std::ofstream out(partial, std::ios::binary);
  const std::int32_t header[3] = {dn.channels[0].width, dn.channels[0].height,
                                  static_cast<std::int32_t>(dn.channels.size())};
  out.write(reinterpret_cast<const char*>(header), sizeof header);
  for (const imaging::Plane& p : dn.channels)
    for (const float v : p.pixels) {
      const auto sample = static_cast<std::uint16_t>(std::clamp(v, 0.0f, 65535.0f));
      out.write(reinterpret_cast<const char*>(&sample), sizeof sample);
    }
  out.close();
  fs::rename(partial, path);  // whole, or not there
}

std::optional<imaging::Image> kept_frame(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::int32_t header[3];
  if (!in.read(reinterpret_cast<char*>(header), sizeof header)) return std::nullopt;
  imaging::Image dn;
  for (int c = 0; c < header[2]; ++c) {
    imaging::Plane p(header[0], header[1]);
    for (float& v : p.pixels) {
      std::uint16_t sample = 0;
      if (!in.read(reinterpret_cast<char*>(&sample), sizeof sample)) return std::nullopt;
      v = sample;
    }
    dn.channels.push_back(std::move(p));
  }
  return dn;
}

/// `flutterscan deblur --decode`'s reading of a frame (its picture beyond the windows aside),
/// its log the session's shape: the second pass's line under "second_pass".
bench::SessionRead cascade_read(const imaging::Image& dn, imaging::CaptureModel model,
                                const session::SecondPassTries& tries) {
  auto frame = imaging::MotionFrame::make(imaging::dn_to_electrons(dn, model), model.direction);
  if (!frame.ok()) throw std::runtime_error(frame.error());
  constexpr double kTolerance = 0.10;  // deblur's default for codes of two or more LEDs
  if (imaging::refinement_fits(model, kTolerance, frame.value().along())) {
    imaging::MotionRefinementOptions refine;
    refine.tolerance = kTolerance;
    const auto refined = imaging::refine_motion(frame.value(), model, refine);
    if (refined.ok() && imaging::refinement_usable(refined.value()))
      model = imaging::with_refined_motion(std::move(model), refined.value());
  }
  imaging::DeblurOptions options;
  options.threads = 1;
  auto deblurred = imaging::deblur(frame.value(), model, options);
  if (!deblurred.ok()) throw std::runtime_error(deblurred.error());
  imaging::Plane motion_latent = std::move(deblurred.value().latent);
  imaging::Plane camera_latent = frame.value().to_camera(motion_latent);
  nlohmann::json log;
  reader::ReaderOptions reader_options;
  reader_options.area = reader::DecodeArea::kFrame;  // deblur's default
  bench::SessionRead read;
  read.readout = session::read_with_cascade({frame.value(), model, motion_latent, &camera_latent},
                                            imaging::Plane{}, reader_options, tries, log);
  read.log["second_pass"] = std::move(log);  // as a session's line holds it
  return read;
}

/// A session path's second-pass credit per frame: offline every window; at a
/// frame rate, what the line's two workers leave at that rate (bench::line_credit_ms).
double second_pass_credit_ms(const std::string& path) {
  constexpr int kWorkers = 2;
  if (path == "session-30fps") return bench::line_credit_ms(30, kWorkers);
  if (path == "session-60fps") return bench::line_credit_ms(60, kWorkers);
  return session::kMaxSecondPassMs;
}

/// The 95% upper bound of a rate seen as `k` of `n`: the rule of three where
/// k = 0, else the Wilson score bound.
double upper_bound(int k, int n) {
  if (n == 0) return 1;
  if (k == 0) return 3.0 / n;
  const double z = 1.96, p = static_cast<double>(k) / n;
  const double centre = p + z * z / (2 * n);
  const double spread = z * std::sqrt(p * (1 - p) / n + z * z / (4.0 * n * n));
  return (centre + spread) / (1 + z * z / n);
}

std::string rate(int k, int n) {
  std::ostringstream s;
  s << k << " / " << n << " (<= " << std::setprecision(2) << upper_bound(k, n) << ")";
  return s.str();
}

int run(const Options& o) {
  const auto started = std::chrono::steady_clock::now();
  std::cout << "CPU: " << bench::cpu_model() << " (1 thread; other jobs may share the machine)\n";
  int shard = 0, shards = 1;
  if (std::sscanf(o.shard.c_str(), "%d/%d", &shard, &shards) != 2 || shards < 1 || shard < 0 ||
      shard >= shards) {
    std::cerr << "misread_bench: --shard must be K/N with 0 <= K < N, not '" << o.shard << "'\n";
    return 2;
  }
  std::vector<std::pair<std::string, session::SecondPassTries>> tries_sets;
  {
    std::istringstream in(o.tries);
    for (std::string name; std::getline(in, name, ';');) {
      std::string problem;
      const auto tries = name == "default" ? std::optional{session::SecondPassTries{}}
                                           : session::parse_second_pass_tries(name, problem);
      if (!tries) {
        std::cerr << "misread_bench: --tries: " << problem << "\n";
        return 2;
      }
      tries_sets.emplace_back(name == "default" ? session::second_pass_tries_name(*tries) : name,
                              *tries);
    }
  }
  std::vector<Subject> subjects;
  for (const std::string& dir : o.photos) {
    auto found = photo_subjects(dir);
    if (found.empty()) std::cout << "no photos in '" << dir << "': skipped\n";
    subjects.insert(subjects.end(), found.begin(), found.end());
  }
  if (subjects.empty()) {
    std::cout << "misread: skipped: no photo folder (give --photos)\n";
    return 0;
  }
  for (Subject& s : rendered_negatives()) subjects.push_back(std::move(s));
  std::erase_if(subjects,
                [&](const Subject& s) { return s.name.find(o.match) == std::string::npos; });
  std::vector<Subject> mine;
  for (std::size_t i = 0; i < subjects.size(); ++i)
    if (static_cast<int>(i) % o.every == 0 && static_cast<int>(i / o.every) % shards == shard)
      mine.push_back(std::move(subjects[i]));

  std::vector<Report> reports;
  std::vector<FrameRun> runs;
  for (Subject& subject : mine) {
    if (subject.photo) {
      // What the decoders read on the photo file itself, backed or not (the
      // ceiling does not move with the evidence rule).
      const auto original =
          reader::read_codes(bench::photo_file_grey(subject.spec.content), {},
                             imaging::Direction::kPlusX, reader::whole_frame_options())
              .readout;
      for (const auto* codes : {&original.codes, &original.unconfirmed})
        for (const reader::DecodedCode& c : *codes) {
          if (c.text == subject.text)
            subject.original_reads = true;
          else
            subject.seconds.insert(c.text);
        }
    }
    for (const double turn : o.turns) {
      subject.spec.rotate_deg = turn;
      for (const std::string& scene : o.scenes) {
        // Rendered once, and only where a frame is not kept already.
        std::optional<Result<std::vector<imaging::Plane>, std::string>> bands;
        auto rendered = [&]() -> const Result<std::vector<imaging::Plane>, std::string>& {
          if (!bands) bands = render_bands(subject, scene == "colour");
          return *bands;
        };
        for (const double electrons : o.electrons)
          for (const std::string& motion : o.motions)
            for (int seed = 0; seed < o.seeds; ++seed) {
              const bench::SessionLine line(subject.spec.width, subject.spec.height, kBlurPx,
                                            electrons);
              const std::uint64_t noise_seed =
                  std::hash<std::string>{}(subject.name + scene + motion) +
                  static_cast<std::uint64_t>(electrons) +
                  static_cast<std::uint64_t>(seed) * 0x9E3779B97F4A7C15ULL +
                  static_cast<std::uint64_t>(turn * 1000);
              std::ostringstream key;
              key << subject.name << "-" << scene << "-" << electrons << "-" << motion << "-"
                  << seed << "-" << turn << ".raw";
              const fs::path kept = fs::path(o.frames) / key.str();
              std::optional<imaging::Image> dn;
              if (!o.frames.empty()) dn = kept_frame(kept);
              if (!dn) {
                if (!rendered().ok()) {
                  std::cerr << subject.name << ": " << rendered().error() << "\n";
                  continue;
                }
                dn = sim::record_frame(
                    expected(rendered().value(), line.model(), motion, noise_seed), line.model(),
                    noise_seed);
                if (!o.frames.empty()) keep_frame(kept, *dn);
              }
              for (const auto& [tries_name, tries] : tries_sets)
                for (const std::string& path : o.paths) {
                  const auto t0 = std::chrono::steady_clock::now();
                  bench::SessionRead read;
                  if (path != "cascade") {
                    const bench::SessionLine session(
                        subject.spec.width, subject.spec.height, kBlurPx, electrons,
                        reader::ReaderOptions{}.area, tries, second_pass_credit_ms(path));
                    read = session.read(*dn);
                  } else {
                    read = cascade_read(*dn, line.model(), tries);
                  }
                  const reader::BarcodeReadout& readout = read.readout;
                  FrameRun run{subject.name,
                               scene,
                               motion,
                               path,
                               tries_name,
                               electrons,
                               !subject.text.empty(),
                               false,
                               subject.original_reads};
                  run.windows = read.windows();
                  run.ms = std::chrono::duration<double, std::milli>(
                               std::chrono::steady_clock::now() - t0)
                               .count();
                  // One symbol read twice is one report; a value held back is
                  // counted only where the frame reported it nowhere.
                  std::set<std::string> seen;
                  for (const bool held : {false, true})
                    for (const reader::DecodedCode& code :
                         held ? readout.unconfirmed : readout.codes) {
                      if (!seen.insert(code.text).second) continue;
                      std::string verdict;
                      if (subject.text.empty())
                        verdict = "unexpected";
                      else if (code.text == subject.text)
                        verdict = "right";
                      else if (subject.seconds.contains(code.text))
                        verdict = "second";
                      else
                        verdict = "misread";
                      run.read_right |= !held && verdict == "right";
                      if (!held && (verdict == "misread" || verdict == "unexpected"))
                        std::cerr << "\n"
                                  << verdict << ": " << path << " " << tries_name << " "
                                  << subject.name << " " << scene << " " << electrons << " e- "
                                  << motion << " seed " << seed << ": " << code.text << " ("
                                  << code.format << ", " << code.decoder << ", " << code.pass
                                  << ", evidence " << code.evidence << ")\n";
                      reports.push_back({subject.name, scene, motion, path, tries_name, code.text,
                                         code.format, code.decoder, code.pass, code.evidence,
                                         verdict, electrons, turn, seed, held});
                    }
                  runs.push_back(run);
                }
            }
      }
    }
    std::cerr << "." << std::flush;
  }
  std::cerr << "\n";

  std::cout << "subjects: " << mine.size() << " (shard " << o.shard << ", every " << o.every
            << "); scenes x light x motion x seeds x turns per subject\n\n";
  // Totals per path and tries.
  std::cout << "| path | tries | frames with a code | right reads | of the ceiling's frames | "
               "misreads per read | photos misread | frames with no code | unexpected per "
               "frame | windows with no code | unexpected per window | held back: right, wrong | "
               "ms per frame (median) |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& [tries_name, tries] : tries_sets)
    for (const std::string& path : o.paths) {
      int positives = 0, right = 0, ceiling = 0, ceiling_read = 0, negatives = 0,
          negative_windows = 0;
      std::vector<double> ms;
      for (const FrameRun& r : runs) {
        if (r.path != path || r.tries != tries_name) continue;
        ms.push_back(r.ms);
        if (r.positive) {
          ++positives;
          right += r.read_right;
          ceiling += r.ceiling;
          ceiling_read += r.ceiling && r.read_right;
        } else {
          ++negatives;
          negative_windows += r.windows;
        }
      }
      int misreads = 0, unexpected = 0, reads = 0, held_right = 0, held_wrong = 0;
      std::set<std::string> misread_photos;
      for (const Report& r : reports) {
        if (r.path != path || r.tries != tries_name) continue;
        if (r.held) {
          held_right += r.verdict == "right";
          held_wrong += r.verdict == "misread" || r.verdict == "unexpected";
          continue;
        }
        reads += r.verdict != "unexpected";
        if (r.verdict == "misread") {
          ++misreads;
          misread_photos.insert(r.subject);
        }
        unexpected += r.verdict == "unexpected";
      }
      std::sort(ms.begin(), ms.end());
      std::set<std::string> positive_subjects;
      for (const FrameRun& r : runs)
        if (r.positive) positive_subjects.insert(r.subject);
      std::cout << "| " << path << " | " << tries_name << " | " << positives << " | " << right
                << " | " << ceiling_read << " / " << ceiling << " | " << rate(misreads, reads)
                << " | "
                << rate(static_cast<int>(misread_photos.size()),
                        static_cast<int>(positive_subjects.size()))
                << " | " << negatives << " | " << rate(unexpected, negatives) << " | "
                << negative_windows << " | " << rate(unexpected, negative_windows) << " | "
                << held_right << ", " << held_wrong << " | " << std::fixed << std::setprecision(0)
                << (ms.empty() ? 0 : ms[ms.size() / 2]) << std::defaultfloat << " |\n";
    }
  // Per try and decoder: what each reported, right and wrong.
  std::cout << "\nBy the latent a value was read on (pass) and its decoder; held back: "
               "values no second reading backed, logged as unconfirmed\n\n"
               "| path | tries | pass | decoder | right | second | misread | unexpected | "
               "held back right | held back wrong |\n|---|---|---|---|---|---|---|---|---|---|\n";
  std::map<std::vector<std::string>, std::map<std::string, int>> by;
  for (const Report& r : reports)
    ++by[{r.path, r.tries, r.pass, r.decoder}]
        [r.held ? (r.verdict == "right" ? "held right" : "held wrong") : r.verdict];
  for (auto& [key, counts] : by)
    std::cout << "| " << key[0] << " | " << key[1] << " | " << key[2] << " | " << key[3] << " | "
              << counts["right"] << " | " << counts["second"] << " | " << counts["misread"] << " | "
              << counts["unexpected"] << " | " << counts["held right"] << " | "
              << counts["held wrong"] << " |\n";
  std::cout << "\nEvery misread and unexpected read\n\n"
               "| path | tries | subject | scene | e- | motion | seed | turn | read | format | "
               "decoder | pass | evidence | truth |\n"
               "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  std::map<std::string, std::string> truth;
  for (const Subject& s : mine) truth[s.name] = s.text;
  for (const Report& r : reports)
    if (!r.held && (r.verdict == "misread" || r.verdict == "unexpected"))
      std::cout << "| " << r.path << " | " << r.tries << " | " << r.subject << " | " << r.scene
                << " | " << r.electrons << " | " << r.motion << " | " << r.seed << " | " << r.turn
                << " | " << r.text << " | " << r.format << " | " << r.decoder << " | " << r.pass
                << " | " << r.evidence << " | " << truth[r.subject] << " |\n";
  if (!o.csv.empty()) {
    std::ofstream csv(o.csv);
    csv << "kind,path,tries,subject,scene,electrons,motion,seed,turn,text,format,decoder,pass,"
           "verdict,ms,ceiling,windows,evidence\n";
    for (const Report& r : reports)
      csv << (r.held ? "held," : "read,") << r.path << ",\"" << r.tries << "\"," << r.subject << ","
          << r.scene << "," << r.electrons << "," << r.motion << "," << r.seed << "," << r.turn
          << ",\"" << r.text << "\"," << r.format << "," << r.decoder << "," << r.pass << ","
          << r.verdict << ",,,," << r.evidence << "\n";
    for (const FrameRun& r : runs)
      csv << "frame," << r.path << ",\"" << r.tries << "\"," << r.subject << "," << r.scene << ","
          << r.electrons << "," << r.motion << ",,,,,,,"
          << (r.positive ? (r.read_right ? "read" : "no-read") : "negative") << "," << r.ms << ","
          << r.ceiling << "," << r.windows << ",\n";
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::cout << "\nrun time " << std::lround(seconds) << " s\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{"Misreads: every value reported on real photos and print with no code"};
  app.add_option("--photos", o.photos, "photo folders (NAME.txt beside a photo: its code)");
  app.add_option("--electrons", o.electrons, "light levels, e-")->delimiter(',');
  app.add_option("--seeds", o.seeds, "noise draws per frame")->check(CLI::PositiveNumber);
  app.add_option("--motions", o.motions, "continuous, steps, jitter, blur+4%, crosstalk")
      ->delimiter(',')
      ->check(CLI::IsMember({"continuous", "steps", "jitter", "blur+4%", "crosstalk"}));
  app.add_option("--scenes", o.scenes, "colour, grey")
      ->delimiter(',')
      ->check(CLI::IsMember({"colour", "grey"}));
  app.add_option("--turns", o.turns, "photos turned by these degrees")->delimiter(',');
  app.add_option("--paths", o.paths, "session, session-30fps, session-60fps, cascade")
      ->delimiter(',')
      ->check(CLI::IsMember({"session", "session-30fps", "session-60fps", "cascade"}));
  app.add_option("--tries", o.tries, "second-pass try sets, ';'-separated (default, all, ...)");
  app.add_option("--every", o.every, "every N-th subject")->check(CLI::PositiveNumber);
  app.add_option("--match", o.match, "subjects whose name (FOLDER/PHOTO) contains this");
  app.add_option("--shard", o.shard, "K/N: the K-th of N interleaved parts (0-based)");
  app.add_option("--csv", o.csv, "every read and frame as CSV");
  app.add_option("--frames", o.frames,
                 "folder to keep the frames in and take them from (a rerun skips rendering)");
  CLI11_PARSE(app, argc, argv);
  if (o.photos.empty()) o.photos = {"../shared/data/real-labels", "../shared/data/real-labels-2"};
  try {
    return run(o);
  } catch (const std::exception& e) {
    std::cerr << "misread_bench: " << e.what() << "\n";
    return 1;
  }
}
