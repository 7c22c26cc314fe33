#include "bench/stability_study.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <mutex>
#include <random>
#include <thread>
#include <tuple>

#include "bench/capture_schemes.hpp"
#include "bench/stability_cyclic_shift.hpp"
#include "codes/library.hpp"
#include "imaging/deblur.hpp"
#include "imaging/exposure_timeline.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/metrics.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/motion_refinement.hpp"
#include "imaging/per_channel_wiener.hpp"
#include "imaging/row_phase_deblur.hpp"
#include "plot/line_chart.hpp"
#include "reader/barcode_reader.hpp"
#include "reader/code_reading.hpp"
#include "reader/reader_options.hpp"
#include "sim/colour_scene.hpp"
#include "sim/forward_model.hpp"
#include "sim/pixel_integration.hpp"
#include "sim/scene.hpp"
#include "sim/speed_profile.hpp"
#include "sim/timeline_forward.hpp"

namespace flutterscan::bench {
namespace {

using imaging::CaptureModel;
using imaging::Image;
using imaging::Plane;

constexpr double kBlur = 52;
constexpr double kCap = 3;
constexpr double kReadNoise = 4;
constexpr double kNominalElectrons = 3000;
constexpr double kSlotTimeUs = 19;  // a 52-slot exposure of 988 us (sequencer: exposure / L)
constexpr double kPassRate = 0.9;   // a method fails where its decode rate drops below this

const std::vector<std::string> kSchemeNames = {"rect-white", "raskar-white", "seed-maxmin-1",
                                               "found-mse"};
const std::vector<std::string> kStandardMethods = {"joint-wiener", "rl", "tv"};

struct Scene {
  std::string content;
  Plane fine;  ///< grey, rendered sim::kSimSupersample times finer than the pixels
  Plane grey;  ///< the truth: what a sharp capture of `fine` records
  std::vector<Plane> red, blue;  ///< colour versions (bands per LED)
};

struct Score {
  double psnr = 0;
  bool decoded = false;
};

struct Trial {
  const CaptureScheme& scheme;
  const Scene& scene;
  int seed;
  std::uint64_t noise_seed;
  double blur_tolerance;  ///< the session's motion refinement (0: off)
};

/// How a factor gets harsher along its x values.
enum class Harsh { kUp, kDown, kBothWays, kCategories };

struct Factor {
  std::string name, title, x_label;
  std::vector<double> xs;
  std::vector<std::string> categories;  ///< for Harsh::kCategories: the name of each x
  Harsh harsh = Harsh::kUp;
  bool log_x = false;
  std::vector<std::string> methods = kStandardMethods;
  std::string extra_group;  ///< methods past the first three form a second chart group
  std::function<std::vector<Score>(double x, const Trial&)> run;
};

Factor named_factor(std::string name, std::string title, std::string x_label) {
  Factor f;
  f.name = std::move(name);
  f.title = std::move(title);
  f.x_label = std::move(x_label);
  return f;
}

CaptureModel nominal_model(const CaptureScheme& scheme, double electrons) {
  return bench_camera(scheme, electrons, kCap, kReadNoise, kBlur);
}

Score judge(const Plane& latent, const Plane& truth, const std::string& content) {
  Score s;
  s.psnr = imaging::psnr(
      truth, latent,
      imaging::scored_region(truth.width, truth.height, kBlur, imaging::Direction::kPlusX));
  // The session's reader options on the whole frame (docs/benchmarks.md says so).
  const auto found = reader::code_texts(
      reader::read_codes(latent, {}, imaging::Direction::kPlusX, reader::whole_frame_options())
          .readout);
  s.decoded = std::find(found.begin(), found.end(), content) != found.end();
  return s;
}

imaging::DeblurOptions options_for(imaging::Method method) {
  imaging::DeblurOptions options;
  options.method = method;
  options.threads = 1;  // frames run in parallel instead
  return options;
}

const imaging::Method kMethods[] = {imaging::Method::kJointWiener, imaging::Method::kRichardsonLucy,
                                    imaging::Method::kTotalVariation};

/// joint-wiener, rl and tv on one frame (electrons) under the model the solver
/// assumes, its motion refined on the frame when the trial says so.
std::vector<Score> standard_methods(const Image& electrons, const CaptureModel& given,
                                    const Plane& truth, const Trial& t) {
  CaptureModel assumed = given;  // its motion refined as the session does, when the trial asks
  if (t.blur_tolerance > 0)
    if (const auto frame = imaging::MotionFrame::make(Image(electrons), given.direction);
        frame.ok())
      assumed = imaging::motion_refined(frame.value(), given, t.blur_tolerance);
  std::vector<Score> scores;
  for (const auto method : kMethods) {
    const auto result = imaging::deblur(electrons, assumed, options_for(method));
    scores.push_back(result.ok() ? judge(result.value().latent, truth, t.scene.content) : Score{});
  }
  return scores;
}

/// Records `expected` under `truth` and reads it back under `assumed`.
Image recorded(const Image& expected, const CaptureModel& truth, const CaptureModel& assumed,
               std::uint64_t seed) {
  return imaging::dn_to_electrons(sim::record_frame(expected, truth, seed), assumed);
}

std::vector<Score> nominal_run(const CaptureModel& truth, const CaptureModel& assumed,
                               const Image& expected, const Trial& t) {
  return standard_methods(recorded(expected, truth, assumed, t.noise_seed), assumed, t.scene.grey,
                          t);
}

std::vector<Factor> make_factors() {
  std::vector<Factor> factors;
  {
    Factor f = named_factor("light", "Light level", "light level E (e- per channel, rect-white)");
    f.xs = {30, 100, 300, 1000, 3000, 10000};
    f.harsh = Harsh::kDown;
    f.log_x = true;
    f.run = [](double x, const Trial& t) {
      const auto m = nominal_model(t.scheme, x);
      return nominal_run(m, m, sim::expected_electrons(t.scene.fine, m, sim::kSimSupersample), t);
    };
    factors.push_back(f);
  }
  {
    Factor f = named_factor("blur-error", "Blur length wrong",
                            "assumed blur length error (% of the true 52 px)");
    f.xs = {-10, -5, -2, 0, 2, 5, 10};
    f.harsh = Harsh::kBothWays;
    f.run = [](double x, const Trial& t) {
      const auto truth = nominal_model(t.scheme, kNominalElectrons);
      auto assumed = truth;
      assumed.blur_px = kBlur * (1 + x / 100);
      return nominal_run(truth, assumed,
                         sim::expected_electrons(t.scene.fine, truth, sim::kSimSupersample), t);
    };
    factors.push_back(f);
  }
  {
    Factor f = named_factor("jitter", "Belt jitter within the exposure",
                            "speed jitter per slot (rms, fraction of the mean speed)");
    f.xs = {0, 0.05, 0.1, 0.2, 0.3, 0.5};
    f.run = [](double x, const Trial& t) {
      const auto m = nominal_model(t.scheme, kNominalElectrons);
      const auto boundaries =
          sim::jittered_slot_boundaries(m.code.length(), kBlur, x, t.noise_seed * 3 + 1);
      const auto segments = imaging::segments_from_boundaries(m.code, boundaries);
      return nominal_run(
          m, m, sim::expected_electrons_timeline(t.scene.fine, m, segments, sim::kSimSupersample),
          t);
    };
    factors.push_back(f);
  }
  {
    Factor f =
        named_factor("acceleration", "Constant acceleration within the exposure",
                     "speed change over the exposure (end minus start, fraction of the mean)");
    f.xs = {0, 0.1, 0.2, 0.4, 0.6, 1.0};
    f.run = [](double x, const Trial& t) {
      const auto m = nominal_model(t.scheme, kNominalElectrons);
      const auto boundaries = sim::accelerated_slot_boundaries(m.code.length(), kBlur, x);
      const auto segments = imaging::segments_from_boundaries(m.code, boundaries);
      return nominal_run(
          m, m, sim::expected_electrons_timeline(t.scene.fine, m, segments, sim::kSimSupersample),
          t);
    };
    factors.push_back(f);
  }
  {
    Factor f = named_factor("crosstalk-error", "Crosstalk matrix wrong",
                            "error of every crosstalk entry (%, random signs per seed)");
    f.xs = {0, 2.5, 5, 10, 15, 20};
    f.run = [](double x, const Trial& t) {
      const auto assumed = nominal_model(t.scheme, kNominalElectrons);
      auto truth = assumed;
      std::mt19937_64 rng(t.noise_seed * 31 + 7);
      for (double& entry : truth.crosstalk) entry *= 1 + (rng() % 2 ? x : -x) / 100;
      return nominal_run(truth, assumed,
                         sim::expected_electrons(t.scene.fine, truth, sim::kSimSupersample), t);
    };
    factors.push_back(f);
  }
  {
    Factor f = named_factor(
        "saturation", "Saturation",
        "white level of the brightest channel / full well (light raised to get there)");
    f.xs = {0.5, 0.8, 1.0, 1.25, 1.5, 2, 3};
    f.run = [](double x, const Trial& t) {
      const auto unit = nominal_model(t.scheme, 1.0);
      double white = 0;
      for (int c = 0; c < 3; ++c)
        white = std::max(white, imaging::channel_white_electrons(unit, c));
      const auto m = nominal_model(t.scheme, x * unit.full_well / white);
      return nominal_run(m, m, sim::expected_electrons(t.scene.fine, m, sim::kSimSupersample), t);
    };
    factors.push_back(f);
  }
  {
    Factor f = named_factor("ambient", "Ambient light (known to the model)",
                            "ambient light (% of each channel's LED light over the exposure)");
    f.xs = {0, 10, 20, 30, 50};
    f.run = [](double x, const Trial& t) {
      auto m = nominal_model(t.scheme, kNominalElectrons);
      for (int c = 0; c < 3; ++c)
        m.ambient_electrons[static_cast<std::size_t>(c)] =
            x / 100 * imaging::channel_white_electrons(m, c);
      return nominal_run(m, m, sim::expected_electrons(t.scene.fine, m, sim::kSimSupersample), t);
    };
    factors.push_back(f);
  }
  {
    Factor f = named_factor("srgb", "sRGB-encoded camera output",
                            "0: linear camera, 1: sRGB read as linear, 2: sRGB linearised");
    f.xs = {0, 1, 2};
    f.categories = {"linear camera", "sRGB read as linear", "sRGB linearised"};
    f.harsh = Harsh::kCategories;
    f.run = [](double x, const Trial& t) {
      auto truth = nominal_model(t.scheme, kNominalElectrons);
      auto assumed = truth;
      if (x > 0.5) truth.encoding = imaging::Encoding::kSrgb;
      if (x > 1.5) assumed.encoding = imaging::Encoding::kSrgb;
      return nominal_run(truth, assumed,
                         sim::expected_electrons(t.scene.fine, truth, sim::kSimSupersample), t);
    };
    factors.push_back(f);
  }
  {
    Factor f = named_factor("colour", "Colour objects: grey model against the per-channel model",
                            "0: grey print, 1: red print, 2: blue print (on white paper)");
    f.xs = {0, 1, 2};
    f.categories = {"grey print", "red print", "blue print"};
    f.harsh = Harsh::kCategories;
    f.methods = {"joint-wiener", "rl", "tv", "per-channel", "print-plane"};
    f.extra_group = "per-channel";
    f.run = [](double x, const Trial& t) {
      const auto m = nominal_model(t.scheme, kNominalElectrons);
      const std::vector<Plane> grey_bands = {t.scene.grey, t.scene.grey, t.scene.grey};
      const auto& bands = x < 0.5 ? grey_bands : x < 1.5 ? t.scene.red : t.scene.blue;
      const Plane truth = sim::fuse_bands(bands);
      const auto expected = sim::expected_colour_electrons(bands, m);
      if (!expected.ok()) return std::vector<Score>(5);
      const auto electrons = recorded(expected.value(), m, m, t.noise_seed);
      auto scores = standard_methods(electrons, m, truth, t);
      for (const auto prior :
           {imaging::ColourPrior::kThreeBands, imaging::ColourPrior::kPrintPlane}) {
        const auto r = imaging::deblur_per_channel(
            imaging::MotionFrame::make(electrons, m.direction).value(), m,
            1.0 / imaging::kLabelGradientVariance, {.threads = 1, .prior = prior});
        scores.push_back(r.ok() ? judge(r.value().grey, truth, t.scene.content) : Score{});
      }
      return scores;
    };
    factors.push_back(f);
  }
  {
    Factor f = named_factor("rolling-shutter", "Rolling shutter (pattern repeated cyclically)",
                            "line time (us; slot time 19 us)");
    f.xs = {0, 1, 2, 5, 10, 20, 30};
    f.methods = {"joint-wiener", "rl", "tv", "joint-wiener per-row", "rl per-row", "tv per-row"};
    f.extra_group = "per-row";
    f.run = [](double x, const Trial& t) {
      const auto m = nominal_model(t.scheme, kNominalElectrons);
      const auto expected =
          sim::expected_rolling_shutter_electrons(t.scene.grey, m, x, kSlotTimeUs);
      if (!expected.ok()) return std::vector<Score>(6);
      const auto electrons = recorded(expected.value(), m, m, t.noise_seed);
      auto scores = standard_methods(electrons, m, t.scene.grey, t);
      std::vector<double> phases;
      for (int y = 0; y < electrons.height(); ++y)
        phases.push_back(sim::rolling_shutter_phase(y, x, kSlotTimeUs, m.code.length()));
      for (const auto method : kMethods) {
        const auto r =
            imaging::deblur_row_phases(imaging::MotionFrame::make(electrons, m.direction).value(),
                                       m, phases, options_for(method));
        scores.push_back(r.ok() ? judge(r.value(), t.scene.grey, t.scene.content) : Score{});
      }
      return scores;
    };
    factors.push_back(f);
  }
  return factors;
}

struct Job {
  std::size_t factor, x, scheme, scene;
  int seed;
};

struct Aggregate {
  double psnr = 0;
  int frames = 0, decoded = 0;
  double mean_psnr() const { return frames ? psnr / frames : 0.0; }
  double rate() const { return frames ? static_cast<double>(decoded) / frames : 0.0; }
};

std::string format_x(const Factor& f, std::size_t i) {
  if (!f.categories.empty()) return f.categories[i];
  char text[32];
  std::snprintf(text, sizeof text, "%g", f.xs[i]);
  return text;
}

/// The threshold text of one curve: where it stops decoding >= 90%.
std::string threshold_text(const Factor& f, const std::vector<Aggregate>& curve) {
  const auto passes = [&](std::size_t i) { return curve[i].rate() >= kPassRate; };
  if (f.harsh == Harsh::kCategories) {
    std::string text;
    for (std::size_t i = 0; i < curve.size(); ++i) {
      char part[96];
      std::snprintf(part, sizeof part, "%s%s %.0f%%", i ? ", " : "", f.categories[i].c_str(),
                    100 * curve[i].rate());
      text += part;
    }
    return text;
  }
  const auto walk = [&](std::vector<std::size_t> order) -> std::string {
    if (!passes(order.front())) return "fails at " + format_x(f, order.front());
    for (std::size_t k = 1; k < order.size(); ++k)
      if (!passes(order[k]))
        return "fails at " + format_x(f, order[k]) + " (holds at " + format_x(f, order[k - 1]) +
               ")";
    return "holds to " + format_x(f, order.back());
  };
  std::vector<std::size_t> up(f.xs.size());
  for (std::size_t i = 0; i < up.size(); ++i) up[i] = i;
  if (f.harsh == Harsh::kUp) return walk(up);
  if (f.harsh == Harsh::kDown) return walk({up.rbegin(), up.rend()});
  const auto zero =
      static_cast<std::size_t>(std::find(f.xs.begin(), f.xs.end(), 0.0) - f.xs.begin());
  std::vector<std::size_t> below, above;
  for (std::size_t i = zero + 1; i-- > 0;) below.push_back(i);
  for (std::size_t i = zero; i < f.xs.size(); ++i) above.push_back(i);
  return "low side " + walk(below) + "; high side " + walk(above);
}

const plot::Rgb kSchemeColours[] = {
    {0.1, 0.1, 0.1}, {0.85, 0.1, 0.1}, {0.1, 0.25, 0.85}, {0.1, 0.6, 0.15}};

/// One chart of the methods [first, last) of a factor: PSNR (failing points
/// drawn large) or decode rate.
std::string write_chart(const Factor& f,
                        const std::vector<std::vector<std::vector<Aggregate>>>& agg,
                        std::size_t first, std::size_t last, bool decode, const std::string& path,
                        const std::string& what, int frames_per_point) {
  plot::LineChart chart;
  chart.title = f.title + (what.empty() ? "" : " (" + what + ")") +
                (decode ? ": barcode decode rate" : ": PSNR");
  chart.x_label = f.x_label;
  chart.y_label = decode ? "decode rate (%)" : "PSNR (dB)";
  chart.log_x = f.log_x;
  if (decode) {
    chart.y_min = -2;
    chart.y_max = 102;
  }
  char note[200];
  std::snprintf(note, sizeof note,
                "colour: scheme (black rect-white, red raskar-white, blue seed-maxmin-1, green "
                "found-mse); %d frames per point",
                frames_per_point);
  chart.notes.push_back(note);
  std::string styles = "line: ";
  for (std::size_t m = first; m < last; ++m)
    styles += f.methods[m] +
              (m - first == 0   ? " thin"
               : m - first == 1 ? " dashed"
                                : " thick") +
              (m + 1 < last ? ", " : "");
  chart.notes.push_back(styles + (decode ? "; grey dashed line: 90%, the failure threshold"
                                         : "; large dots: decode rate < 90% (fails)"));
  for (std::size_t m = first; m < last; ++m)
    for (std::size_t s = 0; s < kSchemeNames.size(); ++s) {
      plot::Series series, failing;
      series.label = f.methods[m] + " " + kSchemeNames[s];
      series.colour = failing.colour = kSchemeColours[s];
      series.dashed = m - first == 1;
      series.line_width = m - first == 2 ? 3.5 : 1.5;
      series.marker_radius = 2.5;
      failing.line_width = 0;
      failing.marker_radius = 6.5;
      for (std::size_t i = 0; i < f.xs.size(); ++i) {
        const Aggregate& a = agg[m][s][i];
        series.x.push_back(f.xs[i]);
        series.y.push_back(decode ? 100 * a.rate() : a.mean_psnr());
        if (!decode && a.rate() < kPassRate) {
          failing.x.push_back(f.xs[i]);
          failing.y.push_back(a.mean_psnr());
        }
      }
      chart.series.push_back(std::move(series));
      if (!failing.x.empty()) chart.series.push_back(std::move(failing));
    }
  if (decode) {
    plot::Series line;
    line.x = {f.xs.front(), f.xs.back()};
    line.y = {100 * kPassRate, 100 * kPassRate};
    line.dashed = true;
    line.line_width = 1;
    line.colour = {0.5, 0.5, 0.5};
    chart.series.push_back(std::move(line));
  }
  return plot::write_png(chart, path);
}

std::string cyclic_shift_table(const std::string& out_dir, std::FILE* report) {
  codes::MeritSettings with_crosstalk;  // the study's light model: 3000 e-, c 3, 4 e-
  with_crosstalk.light.crosstalk =
      codes::Crosstalk{3, 3, {0.90, 0.08, 0.01, 0.10, 0.85, 0.12, 0.01, 0.07, 0.88}};
  const codes::MeritSettings plain;
  const std::string csv_path = out_dir + "/stability-cyclic-shift.csv";
  std::FILE* csv = std::fopen(csv_path.c_str(), "w");
  if (!csv) return "cannot write " + csv_path;
  std::fprintf(csv, "code,merit,unshifted,worst,worst_shift,mean,loss_db\n");
  std::fprintf(
      report,
      "\n### Codes under every cyclic shift (rolling shutter)\n\n"
      "Merits at 3000 e-, c = 3, read noise 4 e- (crosstalk for 3-LED codes); worst = "
      "the worst of the L whole-slot rotations. mse: lower is better.\n\n"
      "| code | joint at shift 0 | worst joint (shift) | loss | mse at shift 0 | worst mse "
      "(shift) | loss | stays good |\n|---|---|---|---|---|---|---|---|\n");
  for (const auto& entry : codes::code_library()) {
    const LedCode code = codes::to_code(entry);
    const auto& settings = code.leds() == 3 ? with_crosstalk : plain;
    const auto joint = cyclic_shift_robustness(code, codes::Merit::kJoint, settings);
    const auto mse = cyclic_shift_robustness(code, codes::Merit::kMse, settings);
    if (!joint.ok() || !mse.ok()) continue;
    const double joint_loss = cyclic_shift_loss_db(codes::Merit::kJoint, joint.value());
    const double mse_loss = cyclic_shift_loss_db(codes::Merit::kMse, mse.value());
    // Good under every shift: the worst rotation's expected deconvolution error (mse)
    // is within 1 dB of the code's own.
    const bool good = mse_loss <= 1.0;
    std::fprintf(report,
                 "| %s | %.3g e- | %.3g e- (%d) | %.1f dB | %.5f | %.5f (%d) | %.2f dB | %s |\n",
                 std::string(entry.name).c_str(), joint.value().unshifted, joint.value().worst,
                 joint.value().worst_shift, joint_loss, mse.value().unshifted, mse.value().worst,
                 mse.value().worst_shift, mse_loss, good ? "yes" : "no");
    for (const auto& [name, r, loss] :
         {std::tuple{"joint", joint.value(), joint_loss}, std::tuple{"mse", mse.value(), mse_loss}})
      std::fprintf(csv, "%s,%s,%.6g,%.6g,%d,%.6g,%.3f\n", std::string(entry.name).c_str(), name,
                   r.unshifted, r.worst, r.worst_shift, r.mean, loss);
  }
  std::fclose(csv);
  return {};
}

}  // namespace

std::vector<std::string> stability_factor_names() {
  std::vector<std::string> names;
  for (const auto& f : make_factors()) names.push_back(f.name);
  names.push_back("cyclic-shift");
  return names;
}

std::string run_stability_study(const StabilityOptions& options, std::FILE* report) {
  const auto all = make_factors();
  std::vector<Factor> factors;
  bool cyclic = options.factors.empty();
  for (const auto& name : options.factors) {
    if (name == "cyclic-shift") {
      cyclic = true;
      continue;
    }
    const auto it =
        std::find_if(all.begin(), all.end(), [&](const Factor& f) { return f.name == name; });
    if (it == all.end()) return "unknown factor '" + name + "'";
    factors.push_back(*it);
  }
  if (options.factors.empty()) factors = all;
  if (options.seeds < 1) return "seeds must be at least 1";

  std::vector<CaptureScheme> schemes;
  for (const auto& scheme : standard_schemes())
    if (std::find(kSchemeNames.begin(), kSchemeNames.end(), scheme.name) != kSchemeNames.end())
      schemes.push_back(scheme);
  std::vector<Scene> scenes;
  for (const auto& [spec_text, content] :
       std::vector<std::pair<std::string, std::string>>{{"code128:FS-0042", "FS-0042"},
                                                        {"ean13:4006381333931", "4006381333931"},
                                                        {"qr:FLUTTERSCAN", "FLUTTERSCAN"},
                                                        {"datamatrix:LOT-2611", "LOT-2611"}}) {
    auto spec = sim::parse_scene(spec_text).value();
    spec.width = options.width;
    spec.height = options.height;
    spec.module_px = 3;
    auto fine = sim::render_scene(spec, sim::kSimSupersample);
    auto red = sim::render_colour_scene(spec, sim::kRedInk);
    auto blue = sim::render_colour_scene(spec, sim::kBlueInk);
    if (!fine.ok()) return spec_text + ": " + fine.error();
    Plane grey = sim::bin_pixels(fine.value(), sim::kSimSupersample);
    if (!red.ok() || !blue.ok()) return spec_text + ": the colour scene failed";
    scenes.push_back({content, std::move(fine.value()), std::move(grey), std::move(red.value()),
                      std::move(blue.value())});
  }

  std::vector<Job> jobs;
  for (std::size_t f = 0; f < factors.size(); ++f)
    for (std::size_t x = 0; x < factors[f].xs.size(); ++x)
      for (std::size_t s = 0; s < schemes.size(); ++s)
        for (std::size_t sc = 0; sc < scenes.size(); ++sc)
          for (int seed = 1; seed <= options.seeds; ++seed) jobs.push_back({f, x, s, sc, seed});
  std::vector<std::vector<Score>> results(jobs.size());
  std::atomic<std::size_t> next{0};
  std::mutex progress;
  std::size_t done = 0;
  const auto start = std::chrono::steady_clock::now();
  const auto worker = [&] {
    for (std::size_t i; (i = next++) < jobs.size();) {
      const Job& j = jobs[i];
      const Trial trial{schemes[j.scheme], scenes[j.scene], j.seed,
                        static_cast<std::uint64_t>(j.seed) * 7919 + j.scene,
                        options.blur_tolerance_pct / 100};
      results[i] = factors[j.factor].run(factors[j.factor].xs[j.x], trial);
      const std::lock_guard lock(progress);
      if (++done % 20 == 0 || done == jobs.size())
        std::fprintf(
            stderr, "\r  %zu / %zu frames, %.0f s", done, jobs.size(),
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
  };
  {
    std::vector<std::jthread> pool;
    for (int t = 0; t < std::max(1, options.threads); ++t) pool.emplace_back(worker);
  }
  if (!jobs.empty()) std::fprintf(stderr, "\n");
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // agg[factor][method][scheme][x]
  std::vector<std::vector<std::vector<std::vector<Aggregate>>>> agg(factors.size());
  for (std::size_t f = 0; f < factors.size(); ++f)
    agg[f].assign(factors[f].methods.size(),
                  std::vector<std::vector<Aggregate>>(
                      schemes.size(), std::vector<Aggregate>(factors[f].xs.size())));
  for (std::size_t i = 0; i < jobs.size(); ++i)
    for (std::size_t m = 0; m < results[i].size() && m < factors[jobs[i].factor].methods.size();
         ++m) {
      Aggregate& a = agg[jobs[i].factor][m][jobs[i].scheme][jobs[i].x];
      a.psnr += results[i][m].psnr;
      a.decoded += results[i][m].decoded;
      ++a.frames;
    }

  std::fprintf(
      report,
      "## Stability study\n\nNominal: %g e-, cap %g, read noise %g e-, %g px blur along +x, "
      "the bench camera (12 bits, full well 12000 e-, crosstalk); scenes Code 128, EAN-13, "
      "QR, Data Matrix at %dx%d, %d noise seed(s) each (%zu frames per point); fails = "
      "decode rate < 90%%; motion refined on each frame within +-%g%% of the given blur "
      "(0: off). %zu frames in %.0f s on %d threads.\n",
      kNominalElectrons, kCap, kReadNoise, kBlur, options.width, options.height, options.seeds,
      scenes.size() * static_cast<std::size_t>(options.seeds), options.blur_tolerance_pct,
      jobs.size(), seconds, options.threads);
  const int frames_per_point = static_cast<int>(scenes.size()) * options.seeds;
  for (std::size_t f = 0; f < factors.size(); ++f) {
    const Factor& factor = factors[f];
    const std::string stem = options.out_dir + "/stability-" + factor.name;
    if (std::FILE* csv = std::fopen((stem + ".csv").c_str(), "w")) {
      std::fprintf(csv, "factor,x,category,method,scheme,psnr,decode_rate,frames\n");
      for (std::size_t m = 0; m < factor.methods.size(); ++m)
        for (std::size_t s = 0; s < schemes.size(); ++s)
          for (std::size_t x = 0; x < factor.xs.size(); ++x) {
            const Aggregate& a = agg[f][m][s][x];
            std::fprintf(csv, "%s,%g,%s,%s,%s,%.4f,%.4f,%d\n", factor.name.c_str(), factor.xs[x],
                         factor.categories.empty() ? "" : factor.categories[x].c_str(),
                         factor.methods[m].c_str(), schemes[s].name.c_str(), a.mean_psnr(),
                         a.rate(), a.frames);
          }
      std::fclose(csv);
    } else {
      return "cannot write " + stem + ".csv";
    }
    const std::size_t standard = std::min<std::size_t>(3, factor.methods.size());
    for (bool decode : {false, true}) {
      const std::string suffix = decode ? "-decode.png" : ".png";
      if (auto error =
              write_chart(factor, agg[f], 0, standard, decode, stem + suffix,
                          factor.extra_group.empty() ? "" : "global/grey model", frames_per_point);
          !error.empty())
        return error;
      if (factor.methods.size() > standard)
        if (auto error = write_chart(factor, agg[f], standard, factor.methods.size(), decode,
                                     stem + "-" + factor.extra_group + suffix, factor.extra_group,
                                     frames_per_point);
            !error.empty())
          return error;
    }
    std::fprintf(report, "\n### %s (`stability-%s.png`%s)\n\n| method | scheme | PSNR at ",
                 factor.title.c_str(), factor.name.c_str(),
                 factor.extra_group.empty() ? "" : (", `-" + factor.extra_group + ".png`").c_str());
    for (std::size_t x = 0; x < factor.xs.size(); ++x)
      std::fprintf(report, "%s%s", x ? " / " : "", format_x(factor, x).c_str());
    std::fprintf(report, " (dB) | decode rate | threshold |\n|---|---|---|---|---|\n");
    for (std::size_t m = 0; m < factor.methods.size(); ++m)
      for (std::size_t s = 0; s < schemes.size(); ++s) {
        std::fprintf(report, "| %s | %s | ", factor.methods[m].c_str(), schemes[s].name.c_str());
        for (std::size_t x = 0; x < factor.xs.size(); ++x)
          std::fprintf(report, "%s%.1f", x ? " / " : "", agg[f][m][s][x].mean_psnr());
        std::fprintf(report, " | ");
        for (std::size_t x = 0; x < factor.xs.size(); ++x)
          std::fprintf(report, "%s%.0f", x ? " / " : "", 100 * agg[f][m][s][x].rate());
        std::fprintf(report, " | %s |\n", threshold_text(factor, agg[f][m][s]).c_str());
      }
  }
  if (cyclic) return cyclic_shift_table(options.out_dir, report);
  return {};
}

}  // namespace flutterscan::bench
