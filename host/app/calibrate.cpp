// `flutterscan calibrate crosstalk | flat | noise | speed`: the capture model's
// calibrations, printed and optionally written into the [optics] table of a
// session config (--config FILE, comments and other keys kept). Each takes its
// frames either from files on disk (white target frames, flat pairs, coded
// frames of a moving target) or, with --camera, live from the session's camera
// and controller (calibrate_live.hpp). The algorithms live in host/imaging
// (crosstalk_calibration, flat_field, photon_transfer, blur_estimate);
// docs/calibration.md says how to take the frames.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "app/calibrate_live.hpp"
#include "app/cli_errors.hpp"
#include "app/commands.hpp"
#include "app/config_patch.hpp"
#include "app/image_io.hpp"
#include "imaging/blur_estimate.hpp"
#include "imaging/capture_descriptor.hpp"
#include "imaging/crosstalk_calibration.hpp"
#include "imaging/flat_field.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/photon_transfer.hpp"
#include "session/frame_model.hpp"

namespace flutterscan::app {
namespace {

struct CommonFlags {
  int bit_depth = 12;
  std::string config;
  bool json = false;
  LiveFlags live;
};

imaging::Image load(const std::string& path) {
  auto frame = read_frame(path);
  if (!frame.ok()) throw UsageError(frame.error());
  return std::move(frame.value().dn);
}

double full_scale(const CommonFlags& f) {
  return std::pow(2.0, f.bit_depth) - 1;
}

/// Writes `values` into the [optics] table of the config file, atomically.
void update_config(const CommonFlags& f, const std::string& what,
                   const std::vector<std::pair<std::string, std::string>>& values) {
  if (f.config.empty()) return;
  std::string text;
  if (std::filesystem::exists(f.config)) {
    std::ifstream in(f.config);
    if (!in) throw UsageError("cannot read the config '" + f.config + "'");
    std::stringstream buffer;
    buffer << in.rdbuf();
    text = buffer.str();
  }
  const std::string patched =
      patch_toml_table(text, "optics", values, "flutterscan calibrate " + what);
  if (auto error = write_text(f.config, patched); !error.empty()) throw RuntimeFailure(error);
  if (!f.json) std::cout << "wrote [optics] of " << f.config << "\n";
}

void add_common(CLI::App* command, CommonFlags& f) {
  command
      ->add_option("--bit-depth", f.bit_depth,
                   "significant bits per sample of frames from files (live: the camera's)")
      ->check(CLI::Range(8, 16))
      ->capture_default_str();
  command->add_option("--config", f.config,
                      "session config (TOML) whose [optics] table receives the results (live: "
                      "read first for the camera, controller and optics)");
  command->add_flag("--json", f.json, "print one JSON object");
}

// -- crosstalk ---------------------------------------------------------------

struct CrosstalkFlags : CommonFlags {
  std::string dark;
  std::vector<std::string> leds;
};

/// The white-target frames of `calibrate crosstalk` and `calibrate flat`: from
/// --dark and --led, or captured live.
WhiteFrames white_frames(const CommonFlags& f, const std::string& dark,
                         const std::vector<std::string>& leds) {
  check_live_or_files(f.live, !dark.empty() || !leds.empty(), "--dark and --led");
  if (!f.live.camera.empty()) {
    LiveFlags live = f.live;
    live.config = f.config;
    return capture_white_frames(live);
  }
  if (dark.empty())
    throw UsageError("--dark is required with --led (the frame with every LED off)");
  if (leds.empty()) throw UsageError("--led is required with --dark (one frame per LED lit alone)");
  WhiteFrames frames;
  frames.dark = load(dark);
  for (const auto& path : leds) frames.lit.push_back(load(path));
  frames.full_scale_dn = full_scale(f);
  return frames;
}

void run_crosstalk(const CrosstalkFlags& f) {
  const WhiteFrames frames = white_frames(f, f.dark, f.leds);
  const auto result = imaging::calibrate_crosstalk(frames.dark, frames.lit, frames.full_scale_dn);
  if (!result.ok()) throw UsageError(result.error());
  const auto& cal = result.value();
  if (f.json) {
    nlohmann::json matrix = nlohmann::json::array();
    for (int c = 0; c < cal.channels; ++c) {
      nlohmann::json row = nlohmann::json::array();
      for (int k = 0; k < cal.leds; ++k)
        row.push_back(cal.crosstalk[static_cast<std::size_t>(c * cal.leds + k)]);
      matrix.push_back(row);
    }
    std::cout << nlohmann::json{{"crosstalk", matrix},
                                {"led_strength_dn", cal.led_strength_dn},
                                {"black_level_dn", cal.black_level_dn},
                                {"channel_gain", cal.channel_gain},
                                {"condition_number", cal.condition_number},
                                {"warning", cal.warning}}
                     .dump()
              << "\n";
  } else {
    std::printf("crosstalk M (rows: camera channels, columns: LEDs; each column sums to 1)\n");
    for (int c = 0; c < cal.channels; ++c) {
      std::printf("  ");
      for (int k = 0; k < cal.leds; ++k)
        std::printf(" %7.4f", cal.crosstalk[static_cast<std::size_t>(c * cal.leds + k)]);
      std::printf("\n");
    }
    std::printf("LED strengths (DN over all channels):");
    for (double v : cal.led_strength_dn) std::printf(" %.1f", v);
    std::printf("\nblack levels (DN):");
    for (double v : cal.black_level_dn) std::printf(" %.2f", v);
    std::printf("\nchannel gains (relative):");
    for (double v : cal.channel_gain) std::printf(" %.3f", v);
    std::printf("\ncondition number of M: %.2f\n", cal.condition_number);
    if (!cal.warning.empty()) std::cerr << "warning: " << cal.warning << "\n";
  }
  double black = 0;
  for (double v : cal.black_level_dn) black += v / static_cast<double>(cal.black_level_dn.size());
  update_config(f, "crosstalk",
                {{"crosstalk", toml_number_matrix(cal.crosstalk, cal.channels)},
                 {"black_level_dn", toml_number(black)}});
}

// -- flat --------------------------------------------------------------------

struct FlatFlags : CommonFlags {
  std::string dark;
  std::vector<std::string> leds;
  std::string grid = "8x6";
  std::string output;
};

void run_flat(const FlatFlags& f) {
  int tiles_x = 0, tiles_y = 0;
  char separator = 0;
  std::istringstream grid(f.grid);
  if (!(grid >> tiles_x >> separator >> tiles_y) || separator != 'x' || !grid.eof())
    throw UsageError("--grid must be COLUMNSxROWS, e.g. 8x6, not '" + f.grid + "'");
  const WhiteFrames frames = white_frames(f, f.dark, f.leds);
  const auto flat =
      imaging::measure_flat_field(frames.dark, frames.lit, tiles_x, tiles_y, frames.full_scale_dn);
  if (!flat.ok()) throw UsageError(flat.error());
  if (auto error = write_text(f.output, imaging::flat_field_to_json(flat.value()).dump(1) + "\n");
      !error.empty())
    throw RuntimeFailure(error);
  const auto& v = flat.value();
  if (f.json) {
    std::cout << nlohmann::json{{"output", f.output},
                                {"tiles", {v.tiles_x, v.tiles_y}},
                                {"largest_deviation", v.largest_deviation}}
                     .dump()
              << "\n";
  } else {
    std::printf("wrote %s: %dx%d tiles; the light varies by up to %.1f%% across the field\n",
                f.output.c_str(), v.tiles_x, v.tiles_y, 100 * v.largest_deviation);
    for (int k = 0; k < v.leds; ++k) {
      std::printf("LED %d, relative to the median over the tiles (rows of tiles):\n", k);
      const auto d = static_cast<std::size_t>(k * v.leds + k);
      for (int ty = 0; ty < v.tiles_y; ++ty) {
        std::printf("  ");
        for (int tx = 0; tx < v.tiles_x; ++tx)
          std::printf(" %5.3f", v.mixing[static_cast<std::size_t>(ty * v.tiles_x + tx) *
                                             static_cast<std::size_t>(v.leds * v.leds) +
                                         d] /
                                    v.reference[d]);
        std::printf("\n");
      }
    }
  }
  // The path as the session will open it: absolute, in a TOML basic string.
  std::string path = std::filesystem::absolute(f.output).string(), quoted = "\"";
  for (char c : path) quoted += (c == '"' || c == '\\') ? std::string("\\") + c : std::string(1, c);
  update_config(f, "flat", {{"flat_field", quoted + "\""}});
}

// -- noise -------------------------------------------------------------------

struct NoiseFlags : CommonFlags {
  std::vector<std::string> dark;
  std::vector<std::string> flats;  ///< pairs, in order
  std::vector<int> lit_slots = {2, 4, 8, 16};
};

/// The photon transfer frames: from --dark and --flat, or captured live.
NoiseFrames noise_frames(const NoiseFlags& f) {
  check_live_or_files(f.live, !f.dark.empty() || !f.flats.empty(), "--dark and --flat");
  if (!f.live.camera.empty()) {
    if (f.lit_slots.size() < 2) throw UsageError("--lit-slots needs two or more light levels");
    LiveFlags live = f.live;
    live.config = f.config;
    return capture_noise_frames(live, f.lit_slots);
  }
  if (f.dark.size() != 2) throw UsageError("--dark takes two frames (a pair without light)");
  if (f.flats.size() < 4 || f.flats.size() % 2 != 0)
    throw UsageError("give two or more --flat pairs (two frames each), at different light levels");
  NoiseFrames frames;
  frames.dark = {load(f.dark[0]), load(f.dark[1])};
  for (std::size_t i = 0; i < f.flats.size(); i += 2)
    frames.flats.push_back({load(f.flats[i]), load(f.flats[i + 1])});
  frames.full_scale_dn = full_scale(f);
  return frames;
}

void run_noise(const NoiseFlags& f) {
  const NoiseFrames frames = noise_frames(f);
  const auto result = imaging::photon_transfer(frames.dark, frames.flats, frames.full_scale_dn);
  if (!result.ok()) throw UsageError(result.error());
  const auto& ptc = result.value();
  double gain = 0, read_noise = 0;
  const auto channels = static_cast<double>(ptc.gain_e_per_dn.size());
  for (std::size_t c = 0; c < ptc.gain_e_per_dn.size(); ++c) {
    gain += ptc.gain_e_per_dn[c] / channels;
    read_noise += ptc.read_noise_e[c] / channels;
  }
  if (f.json) {
    nlohmann::json points = nlohmann::json::array();
    for (const auto& channel : ptc.points) {
      nlohmann::json list = nlohmann::json::array();
      for (const auto& p : channel)
        list.push_back(
            {{"mean_dn", p.mean_dn}, {"variance_dn2", p.variance_dn2}, {"fitted", p.fitted}});
      points.push_back(list);
    }
    std::cout << nlohmann::json{{"gain_e_per_dn", ptc.gain_e_per_dn},
                                {"read_noise_e", ptc.read_noise_e},
                                {"black_level_dn", ptc.black_level_dn},
                                {"points", points}}
                     .dump()
              << "\n";
  } else {
    for (std::size_t c = 0; c < ptc.gain_e_per_dn.size(); ++c)
      std::printf(
          "channel %zu: gain %.4f e-/DN, read noise %.2f e-, black level %.2f DN (%d of %zu "
          "levels fitted)\n",
          c, ptc.gain_e_per_dn[c], ptc.read_noise_e[c], ptc.black_level_dn[c],
          static_cast<int>(std::count_if(ptc.points[c].begin(), ptc.points[c].end(),
                                         [](const auto& p) { return p.fitted; })),
          ptc.points[c].size());
  }
  update_config(f, "noise",
                {{"gain_e_per_dn", toml_number(gain)}, {"read_noise_e", toml_number(read_noise)}});
}

// -- speed -------------------------------------------------------------------

struct SpeedFlags : CommonFlags {
  std::vector<std::string> frames;
  std::vector<double> encoder_counts;
  double min_blur = 4, max_blur = 200;
};

/// One coded frame to estimate the blur of: electrons (black level removed),
/// its model, and the encoder counts during its exposure (0: none).
struct SpeedSample {
  std::string label;
  imaging::Image electrons;
  imaging::CaptureModel model;
  double counts = 0;
};

/// Frames from files, each with its capture descriptor (FRAME.json).
std::vector<SpeedSample> speed_samples_from_files(const SpeedFlags& f) {
  if (!f.encoder_counts.empty() && f.encoder_counts.size() != f.frames.size())
    throw UsageError("--encoder-counts needs one count per frame (" +
                     std::to_string(f.frames.size()) + " frames, " +
                     std::to_string(f.encoder_counts.size()) + " counts)");
  std::vector<SpeedSample> samples;
  for (std::size_t i = 0; i < f.frames.size(); ++i) {
    const std::string descriptor_path = sibling_path(f.frames[i], "", ".json");
    const auto descriptor = read_json(descriptor_path);
    if (!descriptor.ok())
      throw UsageError("frame '" + f.frames[i] +
                       "' needs its capture descriptor: " + descriptor.error());
    auto model = imaging::from_descriptor(descriptor.value());
    if (!model.ok()) throw UsageError("descriptor '" + descriptor_path + "': " + model.error());
    const auto frame = read_frame(f.frames[i]);
    if (!frame.ok()) throw UsageError(frame.error());
    samples.push_back({f.frames[i], imaging::dn_to_electrons(frame.value().dn, model.value()),
                       model.value(), f.encoder_counts.empty() ? 0.0 : f.encoder_counts[i]});
  }
  return samples;
}

/// Frames captured live under the session's code, modelled from their exposure
/// events and the config's optics; the counts are the events' encoder deltas.
std::vector<SpeedSample> speed_samples_live(const SpeedFlags& f) {
  LiveFlags live = f.live;
  live.config = f.config;
  const SpeedFrames captured = capture_speed_frames(live);
  std::vector<SpeedSample> samples;
  for (const auto& frame : captured.frames) {
    const auto format = frame.format.pixel_format;
    if (capture::is_bayer_mosaic(format))
      throw UsageError("camera " + captured.config.camera.spec +
                       " delivers raw Bayer frames: the blur estimate needs the channels apart "
                       "(configure an RGB pixel format for calibrate speed)");
    const std::string label = "frame " + std::to_string(frame.sequence) + " (exposure " +
                              std::to_string(frame.event.frame_counter) + ")";
    auto model = session::frame_model(frame.event, captured.config.controller.parsed_code,
                                      captured.config, frame.format);
    if (!model.ok()) throw RuntimeFailure(label + ": " + model.error());
    samples.push_back({label, imaging::dn_to_electrons(frame.dn, model.value()), model.value(),
                       std::abs(static_cast<double>(frame.event.encoder_delta))});
  }
  return samples;
}

void run_speed(const SpeedFlags& f) {
  check_live_or_files(f.live, !f.frames.empty(), "frame files");
  if (!f.live.camera.empty() && !f.encoder_counts.empty())
    throw UsageError(
        "--encoder-counts is for frames from files: live, the counts come from the "
        "controller's exposure events");
  if (!(f.max_blur > f.min_blur)) throw UsageError("--max-blur must exceed --min-blur");
  const bool live = !f.live.camera.empty();
  const std::vector<SpeedSample> samples =
      live ? speed_samples_live(f) : speed_samples_from_files(f);
  nlohmann::json per_frame = nlohmann::json::array();
  double weighted_ratio = 0, weights = 0, blur_sum = 0, blur_weights = 0;
  for (const auto& sample : samples) {
    const auto frame = imaging::MotionFrame::make(sample.electrons, sample.model.direction);
    if (!frame.ok()) throw UsageError("'" + sample.label + "': " + frame.error());
    const auto estimate =
        imaging::estimate_blur(frame.value(), sample.model, f.min_blur, f.max_blur);
    if (!estimate.ok()) throw UsageError("'" + sample.label + "': " + estimate.error());
    const auto& e = estimate.value();
    nlohmann::json entry = {{"frame", sample.label}, {"blur_px", e.blur_px}};
    if (live) entry["encoder_counts"] = sample.counts;
    const bool confident = std::isfinite(e.standard_error_px);
    entry["standard_error_px"] = confident ? nlohmann::json(e.standard_error_px) : nlohmann::json();
    if (confident) {
      const double w = 1.0 / std::max(1e-6, e.standard_error_px * e.standard_error_px);
      blur_sum += w * e.blur_px;
      blur_weights += w;
      if (sample.counts != 0) {
        // px per count = blur / counts; its variance (se / counts)^2.
        const double counts = sample.counts;
        const double wr = counts * counts * w;
        weighted_ratio += wr * e.blur_px / counts;
        weights += wr;
      }
    }
    per_frame.push_back(entry);
    if (!f.json) {
      if (confident)
        std::printf("%s: blur %.3f px +- %.3f (residual %.2f of the noise)\n", sample.label.c_str(),
                    e.blur_px, e.standard_error_px, e.residual_per_sample);
      else
        std::printf("%s: no estimate (the frame has too few edges along the motion)\n",
                    sample.label.c_str());
    }
  }
  if (blur_weights == 0)
    throw UsageError(
        "no frame gave a confident blur estimate: use frames of a textured target "
        "(a label) moving along the belt");
  nlohmann::json report = {{"frames", per_frame},
                           {"blur_px", blur_sum / blur_weights},
                           {"blur_standard_error_px", 1 / std::sqrt(blur_weights)}};
  if (weights > 0) {
    report["px_per_count"] = weighted_ratio / weights;
    report["px_per_count_standard_error"] = 1 / std::sqrt(weights);
  }
  if (f.json) {
    std::cout << report.dump() << "\n";
  } else {
    std::printf("blur %.3f px +- %.3f over %zu frames\n", blur_sum / blur_weights,
                1 / std::sqrt(blur_weights), samples.size());
    if (weights > 0)
      std::printf("pixels per encoder count %.5f +- %.5f\n", weighted_ratio / weights,
                  1 / std::sqrt(weights));
  }
  if (weights > 0)
    update_config(f, "speed", {{"px_per_count", toml_number(weighted_ratio / weights)}});
  else if (!f.config.empty())
    throw UsageError(live ? "--config: no exposure event carried encoder counts (is the encoder "
                            "connected, and the belt moving?), so there is no px_per_count"
                          : "--config needs --encoder-counts: without them there is no "
                            "px_per_count to write");
}

}  // namespace

void add_calibrate(CLI::App& app) {
  CLI::App* calibrate = app.add_subcommand(
      "calibrate",
      "Measure the capture model: crosstalk, flat field, noise, speed; from frames on disk or "
      "live with --camera (docs/calibration.md)");
  calibrate->require_subcommand(1);
  const std::string white_frames_help = "live: frames averaged for the dark frame and for each LED";

  auto xf = std::make_shared<CrosstalkFlags>();
  CLI::App* crosstalk = calibrate->add_subcommand(
      "crosstalk", "LED-to-channel matrix, black levels and channel gains from a white target");
  crosstalk->footer(
      "Live (--camera): with a white target under the camera, belt stopped, it disarms the "
      "controller for dark frames, then per LED uploads 1111.., 2222.., 4444.. (52 slots) as code "
      "7, arms, averages --frames frames, and leaves the controller disarmed with code 0 "
      "selected.");
  crosstalk->add_option("--dark", xf->dark, "frame of the white target with every LED off")
      ->check(CLI::ExistingFile);
  crosstalk
      ->add_option("--led", xf->leds, "one frame per LED lit alone (codes 1111.., 2222.., 4444..)")
      ->check(CLI::ExistingFile);
  add_common(crosstalk, *xf);
  add_live_options(crosstalk, xf->live, white_frames_help);
  crosstalk->callback([xf] { run_crosstalk(*xf); });

  auto ff = std::make_shared<FlatFlags>();
  CLI::App* flat = calibrate->add_subcommand(
      "flat", "Illumination and crosstalk per region of the field of view from a white target");
  flat->footer("Live (--camera): the frames of calibrate crosstalk, taken the same way.");
  flat->add_option("--dark", ff->dark, "frame of the white target with every LED off")
      ->check(CLI::ExistingFile);
  flat->add_option("--led", ff->leds, "one frame per LED lit alone (codes 1111.., 2222.., 4444..)")
      ->check(CLI::ExistingFile);
  flat->add_option("--grid", ff->grid, "tiles across x down")->capture_default_str();
  flat->add_option("-o,--output", ff->output, "flat-field file to write (JSON)")->required();
  flat->add_option("--bit-depth", ff->bit_depth,
                   "significant bits per sample of frames from files (live: the camera's)")
      ->check(CLI::Range(8, 16))
      ->capture_default_str();
  flat->add_flag("--json", ff->json, "print one JSON object");
  flat->add_option("--config", ff->config,
                   "session config (TOML) whose optics.flat_field receives the file's path "
                   "(live: also the camera and controller settings used)");
  add_live_options(flat, ff->live, white_frames_help);
  flat->callback([ff] { run_flat(*ff); });

  auto nf = std::make_shared<NoiseFlags>();
  CLI::App* noise = calibrate->add_subcommand(
      "noise", "Gain (e-/DN) and read noise (e-) by photon transfer (EMVA 1288 style)");
  noise->footer(
      "Live (--camera): with a white target under the camera, a dark pair with the controller "
      "disarmed, then a pair per --lit-slots level (all LEDs lit in that many of 52 slots, "
      "uploaded as code 7); the camera's exposure and gain are not touched.");
  noise->add_option("--dark", nf->dark, "two frames without light")
      ->expected(2)
      ->check(CLI::ExistingFile);
  noise
      ->add_option("--flat", nf->flats,
                   "two frames of a flat target at one light level; repeat per level")
      ->expected(2)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
      ->check(CLI::ExistingFile);
  noise
      ->add_option("--lit-slots", nf->lit_slots,
                   "live: the light levels, as slots of 52 lit by all LEDs (light ~ slots)")
      ->check(CLI::Range(2, 52))
      ->capture_default_str();
  add_common(noise, *nf);
  add_live_options(noise, nf->live, "");
  noise->callback([nf] { run_noise(*nf); });

  auto sf = std::make_shared<SpeedFlags>();
  sf->live.frames = 8;
  CLI::App* speed = calibrate->add_subcommand(
      "speed", "Blur length from coded frames of a moving target, and pixels per encoder count");
  speed->footer(
      "Live (--camera): --frames frames of labels moving on the belt under the session's code "
      "(code 0), each matched to its exposure event, whose encoder delta gives the counts.");
  speed->add_option("frames", sf->frames, "coded frames, each with its descriptor (FRAME.json)")
      ->check(CLI::ExistingFile);
  speed->add_option("--encoder-counts", sf->encoder_counts,
                    "encoder counts during each frame's exposure (one per frame; files only)");
  speed->add_option("--min-blur", sf->min_blur, "shortest blur searched, px")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  speed->add_option("--max-blur", sf->max_blur, "longest blur searched, px")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  add_common(speed, *sf);
  add_live_options(speed, sf->live, "live: coded frames to capture");
  speed->callback([sf] { run_speed(*sf); });
}

}  // namespace flutterscan::app
