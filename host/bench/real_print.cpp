// Real print (issue 13): photographs of real labels as the scene, captured
// through the simulator under the session's coded RGB light, deblurred by
// every method and by the session's default path, and read; each rate is
// against what the reader reads on the photo itself (the ceiling).
//
//   real_print_bench [--photos DIR] [--electrons 300,1000,3000] [--methods LIST]
//                    [--every N] [--match TEXT] [--out DIR] [--pictures N] [--seed K]
//
// DIR holds photos (.png, .jpg, .jpeg, .tif, .tiff), each with NAME.txt beside
// it holding the text its code encodes; default $FLUTTERSCAN_REAL_LABELS, else
// ../shared/data/real-labels (from the repository root, where `make bench`
// runs). Without photos the bench says so and exits 0. Each photo is a photo
// scene (sim/photo_scene.hpp; docs/formats.md): its colours as the reflectance
// under the red, green and blue LEDs ("colour"), and the same scene with the
// bands' mean under all three ("grey"). The capture is the session's default
// (code, crosstalk, read noise 4 e-, cap 3, 12 bits) with 52 px of motion
// along +x. REAL_PRINT_EVERY=N (every N-th photo) and REAL_PRINT_MATCH=TEXT
// (names containing TEXT) subset the set, as --every and --match do. --seed K
// draws every frame's noise again (K > 0; 0 gives the documented figures): a
// photo read at one draw and not at another is marginal at that light.
//
// Prints the CPU, the ceiling, the read rates (method x light x colour/grey),
// the failures by cause and the failures themselves; --out writes every trial
// as CSV (real_print.csv) and pictures of the worst cases (worst-N.png: the
// sharp scene, the frame, the best method's latent).

#include <CLI/CLI.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

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
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "bench/cpu_model.hpp"
#include "bench/real_print_photos.hpp"
#include "bench/real_print_session.hpp"
#include "imaging/deblur.hpp"
#include "imaging/frame_conversion.hpp"
#include "reader/barcode_reader.hpp"
#include "reader/code_reading.hpp"
#include "reader/reader_options.hpp"
#include "sim/colour_scene.hpp"
#include "sim/forward_model.hpp"
#include "sim/photo_scene.hpp"
#include "sim/pixel_integration.hpp"
#include "sim/timeline_forward.hpp"

namespace {

using namespace flutterscan;
namespace fs = std::filesystem;

constexpr double kBlurPx = 52;
constexpr int kSupersample = sim::kSimSupersample;
const std::string kSessionPath = "session";  ///< the session's default path among the methods
/// The same with processing.decode_area = "frame" (codes looked for on the whole frame).
const std::string kSessionFrame = "session (area frame)";

struct Options {
  std::string photos;
  std::vector<double> electrons = {300, 1000, 3000};
  std::vector<std::string> methods = {"joint-wiener", "wiener-avg", "rl", "tv"};
  int every = 1;
  std::string match;
  std::string out;
  int pictures = 4;
  std::uint64_t seed = 0;  ///< added to every frame's noise seed: another draw of the noise
};

/// What the sharp scene shows of a photo's code: the ceiling and the
/// properties a failure is put down to.
struct SharpRead {
  bool original = false;  ///< the reader reads the photo file itself, as stored (the ceiling)
  bool scene = false;     ///< the reader reads the sharp photo scene (linear reflectance)
  std::string format;
  double module_px = 0;
  double skew_deg = 0;  ///< the symbol's turn off the nearest axis, 0..45
  double contrast = 0;  ///< symbol contrast on the sharp scene (reflectance)
  double colour = 0;    ///< mean |band - grey| over the photo: how coloured it is
  /// Texts other than the photo's the reader reads on the photo file or the sharp
  /// scene: second codes on it (an add-on, a neighbour's label).
  std::set<std::string> others;
};

struct Trial {
  std::string photo;
  bool colour = true;
  double electrons = 0;
  std::string method;
  bool read = false;
  std::vector<std::string> others;  ///< texts read other than the photo's
};

/// The texts of `texts` other than `text`.
std::vector<std::string> other_texts(const std::vector<std::string>& texts,
                                     const std::string& text) {
  std::vector<std::string> out;
  for (const std::string& t : texts)
    if (t != text) out.push_back(t);
  return out;
}

bool reads(const reader::BarcodeReadout& readout, const std::string& text) {
  return std::any_of(readout.codes.begin(), readout.codes.end(),
                     [&](const reader::DecodedCode& c) { return c.text == text; });
}

reader::BarcodeReadout read_whole(const imaging::Plane& latent) {
  return reader::read_codes(latent, {}, imaging::Direction::kPlusX, reader::whole_frame_options())
      .readout;
}

SharpRead sharp_read(const bench::RealPhoto& photo, const imaging::Plane& truth,
                     const std::vector<imaging::Plane>& bands) {
  SharpRead s;
  const reader::BarcodeReadout readout = read_whole(truth);
  const reader::BarcodeReadout original = read_whole(bench::photo_file_grey(photo.path));
  s.original = reads(original, photo.text);
  for (const reader::DecodedCode& code : readout.codes) s.scene |= code.text == photo.text;
  for (const auto* read : {&readout, &original})
    for (const std::string& t : other_texts(reader::code_texts(*read), photo.text))
      s.others.insert(t);
  // The code's properties where it reads: on the sharp scene, else on the photo.
  for (const reader::DecodedCode& code : s.scene ? readout.codes : original.codes) {
    if (code.text != photo.text) continue;
    s.format = code.format;
    s.module_px = code.quality.module_px;
    s.contrast = code.quality.symbol_contrast;
    const auto& c = code.quality.corners;
    const double deg =
        std::atan2(c[1].y - c[0].y, c[1].x - c[0].x) * 180 / std::numbers::pi;  // top edge
    const double folded = std::fmod(std::abs(deg), 90.0);
    s.skew_deg = std::min(folded, 90 - folded);
    break;
  }
  const imaging::Plane grey = sim::fuse_bands(bands);
  double sum = 0;
  for (const auto& band : bands)
    for (std::size_t i = 0; i < grey.pixels.size(); ++i)
      sum += std::abs(band.pixels[i] - grey.pixels[i]);
  s.colour = sum / (3.0 * static_cast<double>(grey.pixels.size()));
  return s;
}

/// A scene's frame at one light level.
struct Capture {
  imaging::Image dn;
  imaging::Image electrons;
  imaging::CaptureModel model;
};

/// Expected electrons scale with the light: with no ambient light the forward
/// model is linear in the LEDs' electrons, so one rendering serves every level.
imaging::Image scaled(const imaging::Image& expected, const imaging::CaptureModel& reference,
                      const imaging::CaptureModel& model) {
  const double factor = model.led_electrons[0] / reference.led_electrons[0];
  for (std::size_t k = 0; k < model.led_electrons.size(); ++k)
    if (std::abs(model.led_electrons[k] - factor * reference.led_electrons[k]) >
        1e-9 * model.led_electrons[k])
      throw std::runtime_error("the LEDs' electrons do not scale together with the light level");
  imaging::Image out = expected;
  for (auto& plane : out.channels)
    for (float& v : plane.pixels) v = static_cast<float>(v * factor);
  return out;
}

/// Why a failure happened, first cause that applies: sharp scene (the reader
/// does not read even the sharp scene, in linear reflectance), colour (the grey scene
/// reads with the same method and light), rotation (the symbol turned more than
/// 5 degrees off the motion's axes), fine modules (under 2 px), low contrast
/// (symbol contrast under 0.35), light (the same method reads it at a higher
/// level), else other.
std::string cause(const SharpRead& s, bool colour_scene, bool grey_reads, bool brighter_reads) {
  if (!s.scene) return "sharp scene";
  if (colour_scene && grey_reads) return "colour";
  if (s.skew_deg > 5) return "rotation";
  if (s.module_px < 2) return "fine modules";
  if (s.contrast < 0.35) return "low contrast";
  if (brighter_reads) return "light";
  return "other";
}

/// One row of 8-bit grey: reflectance 0..1 (clipped).
cv::Mat to_mat(const imaging::Plane& p, double scale = 1) {
  cv::Mat m(p.height, p.width, CV_8U);
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x)
      m.at<std::uint8_t>(y, x) =
          static_cast<std::uint8_t>(std::clamp(p.at(x, y) * scale, 0.0, 1.0) * 255 + 0.5);
  return m;
}

/// A frame as a picture: its channels' mean, white at the 99th percentile.
imaging::Plane frame_picture(const imaging::Image& electrons) {
  imaging::Plane frame = sim::fuse_bands(electrons.channels);
  std::vector<float> sorted(frame.pixels.begin(), frame.pixels.end());
  const auto at = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() * 99 / 100);
  std::nth_element(sorted.begin(), at, sorted.end());
  const float white = std::max(1.0f, *at);
  for (float& v : frame.pixels) v /= white;
  return frame;
}

/// The sharp scene, the frame and a latent, side by side.
void write_picture(const fs::path& path, const imaging::Plane& truth, const imaging::Plane& frame,
                   const imaging::Plane& latent) {
  cv::Mat strip;
  cv::hconcat(std::vector<cv::Mat>{to_mat(truth), to_mat(frame), to_mat(latent)}, strip);
  cv::imwrite(path.string(), strip);
}

std::string percent(int n, int of) {
  if (of == 0) return "-";
  std::ostringstream s;
  s << n << "/" << of << " (" << std::lround(100.0 * n / of) << "%)";
  return s.str();
}

int run(const Options& o) {
  const auto started = std::chrono::steady_clock::now();
  std::cout << "CPU: " << bench::cpu_model() << " (1 thread; other jobs may share the machine)\n";
  const auto photos = bench::real_photos(o.photos, o.every, o.match);
  if (!photos.ok()) {
    std::cout << "real print: skipped: " << photos.error() << "\n";
    return 0;
  }
  std::cout << "photos: " << photos.value().size() << " from " << o.photos << "\n\n";

  std::vector<Trial> trials;
  std::map<std::string, SharpRead> sharp;
  struct Worst {
    std::string photo;
    imaging::Plane truth, frame, latent;
  };
  std::vector<Worst> worst;
  const double top_level = *std::max_element(o.electrons.begin(), o.electrons.end());
  for (const bench::RealPhoto& photo : photos.value()) {
    auto scene = bench::photo_scene_spec(photo.path, kBlurPx);
    if (!scene.ok()) {
      std::cout << photo.name << ": " << scene.error() << "\n";
      continue;
    }
    const auto fine = sim::render_photo_bands(scene.value(), kSupersample);
    if (!fine.ok()) {
      std::cout << photo.name << ": " << fine.error() << "\n";
      continue;
    }
    std::vector<imaging::Plane> bands;
    for (const auto& band : fine.value()) bands.push_back(sim::bin_pixels(band, kSupersample));
    const imaging::Plane truth = sim::fuse_bands(bands);
    const SharpRead s = sharp_read(photo, truth, bands);
    sharp[photo.name] = s;
    const imaging::Plane grey_fine = sim::fuse_bands(fine.value());
    const bench::SessionLine line(scene.value().width, scene.value().height, kBlurPx, top_level);
    for (const bool colour : {true, false}) {
      const imaging::CaptureModel& reference = line.model();
      const imaging::Image expected =
          colour ? sim::expected_colour_electrons(fine.value(), reference, kSupersample).value()
                 : sim::expected_electrons(grey_fine, reference, kSupersample);
      for (const double electrons : o.electrons) {
        const bench::SessionLine level(scene.value().width, scene.value().height, kBlurPx,
                                       electrons);
        Capture capture;
        capture.model = level.model();
        const std::uint64_t seed = std::hash<std::string>{}(photo.name) + (colour ? 1 : 2) +
                                   static_cast<std::uint64_t>(electrons) +
                                   o.seed * 0x9E3779B97F4A7C15ULL;
        capture.dn =
            sim::record_frame(scaled(expected, reference, capture.model), capture.model, seed);
        capture.electrons = imaging::dn_to_electrons(capture.dn, capture.model);
        for (const std::string& name : o.methods) {
          imaging::DeblurOptions options;
          options.method = *imaging::method_from_name(name);
          options.threads = 1;
          const auto latent = imaging::deblur(capture.electrons, capture.model, options);
          const reader::BarcodeReadout readout =
              latent.ok() ? read_whole(latent.value().latent) : reader::BarcodeReadout{};
          const bool read = reads(readout, photo.text);
          trials.push_back({photo.name, colour, electrons, name, read,
                            other_texts(reader::code_texts(readout), photo.text)});
          if (s.original && !read && colour && electrons == top_level && name == "tv" &&
              latent.ok())
            worst.push_back(
                {photo.name, truth, frame_picture(capture.electrons), latent.value().latent});
        }
        const bench::SessionLine whole_frame(scene.value().width, scene.value().height, kBlurPx,
                                             electrons, reader::DecodeArea::kFrame);
        for (const auto& [path, session] :
             {std::pair{kSessionPath, &level}, std::pair{kSessionFrame, &whole_frame}}) {
          const std::vector<std::string> session_reads =
              reader::code_texts(session->read(capture.dn).readout);
          trials.push_back({photo.name, colour, electrons, path,
                            std::find(session_reads.begin(), session_reads.end(), photo.text) !=
                                session_reads.end(),
                            other_texts(session_reads, photo.text)});
        }
      }
    }
    std::cerr << "." << std::flush;
  }
  std::cerr << "\n";

  // The ceiling.
  int original = 0, sharp_scene = 0;
  for (const auto& [name, s] : sharp) {
    original += s.original;
    sharp_scene += s.scene;
  }
  std::cout << "| photos | read on the photo file (the ceiling) | read on the sharp scene |\n"
               "|---|---|---|\n| "
            << sharp.size() << " | " << original << " | " << sharp_scene << " |\n\n";

  auto rate = [&](const std::string& method, bool colour, double electrons) {
    int n = 0;
    for (const Trial& t : trials)
      n += t.method == method && t.colour == colour && t.electrons == electrons && t.read &&
           sharp[t.photo].original;
    return n;
  };
  std::vector<std::string> all = o.methods;
  all.push_back(kSessionPath);
  all.push_back(kSessionFrame);
  std::cout << "Read, of the " << original
            << " the photo itself reads (session: the default path, cascade, every second pass; "
               "session (area frame): the same reading the whole frame)\n\n"
               "| method | scene |";
  for (double e : o.electrons) std::cout << " " << e << " e- |";
  std::cout << "\n|---|---|";
  for (std::size_t i = 0; i < o.electrons.size(); ++i) std::cout << "---|";
  std::cout << "\n";
  for (const std::string& method : all)
    for (const bool colour : {true, false}) {
      std::cout << "| " << method << " | " << (colour ? "colour" : "grey") << " |";
      for (double e : o.electrons)
        std::cout << " " << percent(rate(method, colour, e), original) << " |";
      std::cout << "\n";
    }

  // Failures by cause (colour scenes, of the photos the sharp scene reads).
  auto lookup = [&](const std::string& photo, bool colour, double e, const std::string& method) {
    for (const Trial& t : trials)
      if (t.photo == photo && t.colour == colour && t.electrons == e && t.method == method)
        return t.read;
    return false;
  };
  const std::vector<std::string> causes = {"sharp scene",  "colour", "rotation", "fine modules",
                                           "low contrast", "light",  "other"};
  std::cout << "\nFailures by cause (colour scenes; first cause that applies: not even the sharp "
               "scene reads; the grey scene reads; turned > 5 deg; modules < 2 px; contrast < "
               "0.35; reads brighter; other)\n\n| method | light |";
  for (const auto& c : causes) std::cout << " " << c << " |";
  std::cout << "\n|---|---|";
  for (std::size_t i = 0; i < causes.size(); ++i) std::cout << "---|";
  std::cout << "\n";
  std::vector<std::string> failure_lines;
  for (const std::string& method : all)
    for (double e : o.electrons) {
      std::map<std::string, int> counts;
      for (const auto& [name, s] : sharp) {
        if (!s.original || lookup(name, true, e, method)) continue;
        bool brighter = false;
        for (double other : o.electrons) brighter |= other > e && lookup(name, true, other, method);
        const std::string c = cause(s, true, lookup(name, false, e, method), brighter);
        ++counts[c];
        if (method == "tv" || method == kSessionPath) {
          std::ostringstream line;
          line << "| " << method << " | " << e << " | " << name << " | " << s.format << " | "
               << std::fixed << std::setprecision(1) << s.module_px << " | " << s.skew_deg << " | "
               << std::setprecision(2) << s.contrast << " | " << s.colour << " | " << c << " |";
          failure_lines.push_back(line.str());
        }
      }
      std::cout << "| " << method << " | " << e << " |";
      for (const auto& c : causes) std::cout << " " << counts[c] << " |";
      std::cout << "\n";
    }
  std::cout << "\nFailures of tv and the session (colour scenes)\n\n"
               "| method | light | photo | format | module px | turn deg | contrast | colour | "
               "cause |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& line : failure_lines) std::cout << line << "\n";

  // Texts read other than the photo's: a second code the sharp scene or the
  // photo file reads too, or a misread (read on neither).
  std::cout << "\nOther texts read (second: the photo file or the sharp scene reads it too; "
               "misread: neither does)\n\n| method | scene | light | photo | text | |\n"
               "|---|---|---|---|---|---|\n";
  int misreads = 0;
  for (const Trial& t : trials)
    for (const std::string& text : t.others) {
      const bool second = sharp[t.photo].others.contains(text);
      misreads += !second;
      std::cout << "| " << t.method << " | " << (t.colour ? "colour" : "grey") << " | "
                << t.electrons << " | " << t.photo << " | " << text << " | "
                << (second ? "second" : "**misread**") << " |\n";
    }
  std::cout << "\nmisreads: " << misreads << "\n";

  if (!o.out.empty()) {
    fs::create_directories(o.out);
    std::ofstream csv(fs::path(o.out) / "real_print.csv");
    csv << "photo,scene,electrons,method,read,original_read,sharp_read,module_px,turn_deg,"
           "contrast,colour\n";
    for (const Trial& t : trials) {
      const SharpRead& s = sharp[t.photo];
      csv << t.photo << "," << (t.colour ? "colour" : "grey") << "," << t.electrons << ","
          << t.method << "," << t.read << "," << s.original << "," << s.scene << "," << s.module_px
          << "," << s.skew_deg << "," << s.contrast << "," << s.colour << "\n";
    }
    // The worst cases: tv's failures at the top light, fewest methods reading first.
    auto readers = [&](const std::string& photo) {
      int n = 0;
      for (const Trial& t : trials) n += t.photo == photo && t.read;
      return n;
    };
    std::stable_sort(worst.begin(), worst.end(), [&](const Worst& a, const Worst& b) {
      return readers(a.photo) < readers(b.photo);
    });
    for (int i = 0; i < std::min<int>(o.pictures, static_cast<int>(worst.size())); ++i) {
      const fs::path path = fs::path(o.out) / ("worst-" + std::to_string(i + 1) + ".png");
      const Worst& w = worst[static_cast<std::size_t>(i)];
      write_picture(path, w.truth, w.frame, w.latent);
      std::cout << "\n"
                << path.string() << ": " << w.photo << " (sharp scene | frame | tv at " << top_level
                << " e-)";
    }
    std::cout << "\n";
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::cout << "\nrun time " << std::lround(seconds) << " s\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (const char* dir = std::getenv("FLUTTERSCAN_REAL_LABELS"))
    o.photos = dir;
  else
    o.photos = "../shared/data/real-labels";
  if (const char* every = std::getenv("REAL_PRINT_EVERY")) o.every = std::max(1, std::atoi(every));
  if (const char* match = std::getenv("REAL_PRINT_MATCH")) o.match = match;
  CLI::App app{"Real label photos through the simulated coded light: read rates"};
  app.add_option("--photos", o.photos, "folder of photos, each with NAME.txt")
      ->capture_default_str();
  app.add_option("--electrons", o.electrons, "light levels, e-")->delimiter(',');
  app.add_option("--methods", o.methods, "deblurring methods")
      ->delimiter(',')
      ->check(CLI::IsMember({"joint-wiener", "wiener-avg", "rl", "tv"}));
  app.add_option("--every", o.every, "every N-th photo")->check(CLI::PositiveNumber);
  app.add_option("--match", o.match, "photos whose name contains this");
  app.add_option("--out", o.out, "folder for the CSV and the pictures");
  app.add_option("--pictures", o.pictures, "worst cases to picture")->check(CLI::NonNegativeNumber);
  app.add_option("--seed", o.seed, "added to every frame's noise seed (0: the documented figures)");
  CLI11_PARSE(app, argc, argv);
  try {
    return run(o);
  } catch (const std::exception& e) {
    std::cerr << "real_print_bench: " << e.what() << "\n";
    return 1;
  }
}
