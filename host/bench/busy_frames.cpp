// busy_frame_bench: what one worker spends on a frame through the session's
// per-frame path (session::process_frame, the line's default config, one
// thread), on the frames a line sees: a label on a plain belt (the kind of
// frame session_bench's stage table measures), and frames whose every row holds
// print: rendered text of several sizes filling the frame, without and with a
// label among it, and photos filling the frame (the shared photo sets: their
// photos with no code, and photos with a code), colour and grey.
// Each frame is captured as the misread benchmark captures its scenes
// (seed-maxmin-1, c = 3, read noise 4 e-, 12 bits, 52 px along +x, the scene
// moving continuously within each slot). Not a test: `make bench` part `busy`.
//
//   busy_frame_bench [--width W --height H] [--electrons E] [--repeats N]
//                    [--second-pass-ms MS] [--photos DIR,DIR]
//
// Per frame, read with every window decoded and then bounded as a line at 60
// fps on two workers bounds it: each stage the session logs (times_ms; wall
// time on one thread), the windows decoded and left, and the values read.
// The photo frames need ../shared/data (beside the repository; --photos); where
// it is absent they are skipped, said so.

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "bench/cpu_model.hpp"
#include "bench/real_print_photos.hpp"
#include "bench/real_print_session.hpp"
#include "imaging/exposure_timeline.hpp"
#include "session/frame_memory.hpp"
#include "session/session_config.hpp"
#include "sim/colour_scene.hpp"
#include "sim/forward_model.hpp"
#include "sim/photo_scene.hpp"
#include "sim/pixel_integration.hpp"
#include "sim/scene.hpp"
#include "sim/timeline_forward.hpp"

namespace {

using namespace flutterscan;
namespace fs = std::filesystem;

constexpr double kBlurPx = 52;
constexpr int kSupersample = sim::kSimSupersample;
using Bands = std::vector<imaging::Plane>;  ///< reflectance under the red, green and blue LEDs

struct Options {
  int width = 1920, height = 1080;
  double electrons = 3000;
  int repeats = 5;
  double second_pass_ms = -1;  ///< < 0: the credit two workers leave at 60 fps
  std::vector<std::string> photos = {"../shared/data/real-labels-2"};
};

/// A frame's reflectance at kSupersample: every band the belt's.
Bands belt(int width, int height) {
  imaging::Plane plane(width * kSupersample, height * kSupersample);
  std::fill(plane.pixels.begin(), plane.pixels.end(), static_cast<float>(sim::SceneSpec{}.belt));
  return {plane, plane, plane};
}

/// `tile` (bands at kSupersample) laid into `into` with its top-left at camera
/// pixel (x, y), cut at `into`'s edges.
void lay(Bands& into, const Bands& tile, int x, int y) {
  for (std::size_t b = 0; b < into.size(); ++b) {
    const imaging::Plane& from = tile[std::min(b, tile.size() - 1)];
    imaging::Plane& to = into[b];
    for (int ty = 0; ty < from.height; ++ty) {
      const int fy = y * kSupersample + ty;
      if (fy < 0 || fy >= to.height) continue;
      for (int tx = 0; tx < from.width; ++tx) {
        const int fx = x * kSupersample + tx;
        if (fx >= 0 && fx < to.width) to.at(fx, fy) = from.at(tx, ty);
      }
    }
  }
}

Bands rendered(const sim::SceneSpec& spec) {
  auto plane = sim::render_scene(spec, kSupersample);
  if (!plane.ok()) throw std::runtime_error(plane.error());
  return {plane.value()};
}

/// A shipping label: a Code 128 on white paper, as the session bench's belt carries.
Bands label(const std::string& text) {
  auto spec = sim::parse_scene("code128:" + text);
  spec.value().width = 560;
  spec.value().height = 260;
  spec.value().module_px = 3;
  spec.value().print_blur_px = 0.5;
  spec.value().texture = 0.03;
  return rendered(spec.value());
}

/// Rendered print in every row: lines of text of several sizes, as a printed carton carries.
Bands text_print(int width, int height) {
  static const std::vector<std::string> kLines = {
      "FRAGILE HANDLE WITH CARE THIS SIDE UP",  "SHIP TO 4410 RIVERSIDE DR 98052 REF 00713",
      "LOT 2026-11-29 EXP 2027-05 BATCH 88213", "IIII lllll 11111 ||||| 0000 8888 MMMM WWWW",
      "MADE IN EU 24 x 330 ml RECYCLE ME",      "www.example.com/returns 0800 123 456"};
  Bands out = belt(width, height);
  const double sizes[] = {1.5, 2.5, 3.5};
  int line = 0;
  for (int y = 0; y < height;) {
    const double module = sizes[line % 3];
    const int row_height = static_cast<int>(std::lround(module * 7 + 24));
    for (int x = 0; x < width; x += width / 2) {
      sim::SceneSpec spec;
      spec.kind = sim::SceneKind::kText;
      spec.content = kLines[static_cast<std::size_t>(line + x) % kLines.size()];
      spec.module_px = module;
      spec.width = width / 2;
      spec.height = row_height;
      spec.paper = 0.75;
      spec.texture = 0.05;
      spec.print_blur_px = 0.5;
      auto plane = sim::render_scene(spec, kSupersample);
      // A line too long for its box at this size: the next size down.
      if (plane.ok()) lay(out, {plane.value()}, x, y);
    }
    y += row_height;
    ++line;
  }
  return out;
}

/// Photos of `paths` tiled over the frame, each in its own pixels with a seam of belt.
Bands photo_print(const std::vector<std::string>& paths, int width, int height) {
  Bands out = belt(width, height);
  std::size_t next = 0;
  for (int y = 0; y < height && !paths.empty();) {
    int row_height = 0;
    for (int x = 0; x < width && next < paths.size() * 8;) {
      auto spec = sim::parse_scene("photo:" + paths[next++ % paths.size()]);
      const auto size = sim::photo_frame_size(spec.value());
      if (!size.ok()) continue;
      spec.value().width = size.value().first;
      spec.value().height = size.value().second;
      auto bands = sim::render_photo_bands(spec.value(), kSupersample);
      if (!bands.ok()) continue;
      lay(out, bands.value(), x, y);
      x += spec.value().width;
      row_height = std::max(row_height, spec.value().height);
    }
    if (row_height == 0) break;
    y += row_height;
  }
  return out;
}

Bands grey(Bands bands) {
  const imaging::Plane g = sim::fuse_bands(bands);
  return {g, g, g};
}

/// Photos in `dirs` with a .txt beside them (`with_code`) or without.
std::vector<std::string> photos(const std::vector<std::string>& dirs, bool with_code) {
  std::vector<std::string> out;
  for (const std::string& dir : dirs)
    for (const std::string& file : bench::photo_files(dir))
      if (fs::exists(fs::path(file).replace_extension(".txt")) == with_code) out.push_back(file);
  return out;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

int run(const Options& o) {
  session::keep_freed_frame_memory();  // as a session does: frames' planes not page-faulted anew
  std::cout << "CPU: " << bench::cpu_model() << " (one thread)\n";
  const double credit_ms = o.second_pass_ms >= 0 ? o.second_pass_ms : bench::line_credit_ms(60, 2);
  const bench::SessionLine line(o.width, o.height, kBlurPx, o.electrons);  // its model
  std::cout << o.width << " x " << o.height << ", " << o.electrons << " e-, " << kBlurPx
            << " px along +x; second-pass credit " << std::lround(credit_ms)
            << " ms a frame (two workers at 60 fps); medians of " << o.repeats << " runs\n\n";

  std::vector<std::pair<std::string, Bands>> frames;
  {
    Bands one = belt(o.width, o.height);
    lay(one, label("FS-BELT-0042"), o.width / 2 - 280, o.height / 2 - 130);
    frames.emplace_back("label on a plain belt", std::move(one));
  }
  frames.emplace_back("text in every row", text_print(o.width, o.height));
  {
    Bands text = text_print(o.width, o.height);
    lay(text, label("FS-TEXT-0042"), o.width / 2 - 280, o.height / 2 - 130);
    frames.emplace_back("text in every row + a label", std::move(text));
  }
  const std::vector<std::string> codeless = photos(o.photos, false),
                                 labelled = photos(o.photos, true);
  if (codeless.empty() || labelled.empty()) {
    std::cout << "photo frames skipped: no photos in the --photos folders\n\n";
  } else {
    Bands print = photo_print(codeless, o.width, o.height);
    frames.emplace_back("photos with no code, grey", grey(print));
    frames.emplace_back("photos with no code, colour", std::move(print));
    // Photos with a code, twelve spread over the set.
    std::vector<std::string> spread;
    for (std::size_t i = 0; i < labelled.size();
         i += std::max<std::size_t>(1, labelled.size() / 12))
      spread.push_back(labelled[i]);
    Bands coded = photo_print(spread, o.width, o.height);
    frames.emplace_back("photos with codes, grey", grey(coded));
    frames.emplace_back("photos with codes, colour", std::move(coded));
  }

  // Each frame read with every window decoded, then as a line at 60 fps on two
  // workers bounds it (processing.decode_ms "auto": the frame's share of the
  // workers' time less its conversion and deblur, here those of the first runs).
  std::cout << "| frame | decode | convert | deblur | decode | first pass | second pass | "
               "frame | windows | left | values read |\n"
               "|---|---|---|---|---|---|---|---|---|---|---|\n";
  std::uint64_t seed = 1;
  for (const auto& [name, bands] : frames) {
    const auto expected = sim::expected_colour_electrons_timeline(
        bands, line.model(), imaging::slot_segments(line.model()), kSupersample);
    if (!expected.ok()) {
      std::cerr << name << ": " << expected.error() << "\n";
      return 1;
    }
    const imaging::Image dn = sim::record_frame(expected.value(), line.model(), seed++);
    for (const bool bounded : {false, true}) {
      bench::SessionLine session(o.width, o.height, kBlurPx, o.electrons,
                                 reader::ReaderOptions{}.area, session::SecondPassTries{},
                                 credit_ms, bounded ? -1 : session::kMaxDecodeMs);
      if (bounded) session.at_frame_rate(60, 2);
      std::map<std::string, std::vector<double>> stage;
      bench::SessionRead read;
      for (int r = 0; r < o.repeats; ++r) {
        read = session.read(dn);
        const nlohmann::json times = read.log.value("times_ms", nlohmann::json::object());
        for (auto it = times.begin(); it != times.end(); ++it)
          stage[it.key()].push_back(it.value().get<double>());
      }
      const double before_decode = median(stage["convert"]) + median(stage["deblur"]);
      std::string values;
      for (const reader::DecodedCode& c : read.readout.codes) {
        std::string shown = c.text.substr(0, 24);
        std::replace(shown.begin(), shown.end(), '\n', ' ');
        std::replace(shown.begin(), shown.end(), '|', '/');
        values += (values.empty() ? "" : ", ") + shown;
      }
      std::cout << std::fixed << std::setprecision(1) << "| " << name << " | "
                << (bounded
                        ? "bounded at " +
                              std::to_string(std::lround(read.log.value("decode_budget_ms", 0.0))) +
                              " ms"
                        : std::string("every window"))
                << " | " << median(stage["convert"]) << " | " << median(stage["deblur"]) << " | "
                << median(stage["decode"]) << " | " << before_decode + median(stage["decode"])
                << " | " << median(stage["second_pass"]) << " | "
                << before_decode + median(stage["decode"]) + median(stage["second_pass"]) << " | "
                << read.windows() << " | " << read.log.value("decode_left", 0) << " | "
                << (values.empty() ? "none" : values) << " |\n"
                << std::defaultfloat << std::flush;
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{"Busy frames: the session's per-frame path on frames full of print"};
  app.add_option("--width", o.width, "frame width, px")->check(CLI::Range(640, 4096));
  app.add_option("--height", o.height, "frame height, px")->check(CLI::Range(480, 4096));
  app.add_option("--electrons", o.electrons, "light level, e-")->check(CLI::Range(10.0, 1e5));
  app.add_option("--repeats", o.repeats, "runs per frame")->check(CLI::Range(1, 100));
  app.add_option("--second-pass-ms", o.second_pass_ms,
                 "second-pass credit per frame, ms (default: two workers at 60 fps)");
  app.add_option("--photos", o.photos, "photo folders (NAME.txt beside a photo: its code)")
      ->delimiter(',');
  CLI11_PARSE(app, argc, argv);
  try {
    return run(o);
  } catch (const std::exception& e) {
    std::cerr << "busy_frame_bench: " << e.what() << "\n";
    return 1;
  }
}
