// `flutterscan deblur IN.png (--descriptor IN.json | --code DIGITS --blur PX ...) -o OUT.png`
// writes the fused latent image as a 16-bit grey PNG (reflectance 0..1 as
// 0..65535, same size and registration as the input). A raw Bayer RGGB frame
// (one channel, descriptor "bayer": "RGGB") is deblurred on its raw colour
// planes, or demosaicked first with --bayer-mode demosaic (imaging/bayer.hpp).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>

#include "app/cli_errors.hpp"
#include "app/code_arguments.hpp"
#include "app/commands.hpp"
#include "app/image_io.hpp"
#include "codes/code_report.hpp"
#include "imaging/bayer.hpp"
#include "imaging/capture_descriptor.hpp"
#include "imaging/deblur.hpp"
#include "imaging/flat_field.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/metrics.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/motion_refinement.hpp"
#include "reader/barcode_reader.hpp"
#include "reader/code_reading.hpp"
#include "reader/code_regions.hpp"
#include "reader/reader_options.hpp"
#include "session/read_record.hpp"
#include "session/second_pass.hpp"
#include "sim/scene.hpp"

namespace flutterscan::app {
namespace {

struct DeblurFlags {
  std::string input;
  std::string descriptor;
  std::string code;
  double blur = -1;
  double blur_tolerance_pct = -1;  ///< -1: 10 for codes of two or more LEDs, else 0
  std::string direction = "+x";
  std::string pixel_model;  ///< empty: the descriptor's (or box-aperture)
  std::string crosstalk;
  double black_level = 0;
  double gain = 1;
  double read_noise = 4;
  std::string method;  ///< empty: cascade, or tv on a raw Bayer mosaic (the sharpest each allows)
  int iterations = 0;  ///< 0 = the method's default
  std::string edge_prior = "tv";
  std::string bayer_mode = "raw";
  int threads = 2;
  std::string output;
  bool decode = false;
  std::string decode_area = "frame";  ///< --decode-area: labels or frame (reader_options.hpp)
  std::string tries = session::kDefaultSecondPassTries;  ///< --tries: the cascade's second pass's
  bool json = false;
  std::string truth;  ///< ground truth (reflectance x 65535) to score against
  std::string flat;   ///< flat-field file (calibrate flat)
};

double elapsed_ms(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since)
      .count();
}

/// The white level of each channel (e-): the 99.5th percentile, taken as reflectance 1.
std::vector<double> white_levels(const imaging::Image& electrons) {
  std::vector<double> levels;
  for (const auto& plane : electrons.channels) {
    std::vector<float> values(plane.pixels.begin(), plane.pixels.end());
    const auto at = values.begin() +
                    static_cast<std::ptrdiff_t>(0.995 * static_cast<double>(values.size() - 1));
    std::nth_element(values.begin(), at, values.end());
    levels.push_back(std::max(1.0, static_cast<double>(*at)));
  }
  return levels;
}

/// The ground truth at `path`, a 16-bit grey PNG of reflectance x 65535 the
/// size of the output (what `flutterscan simulate` writes beside a frame).
imaging::Plane read_truth(const std::string& path, int width, int height) {
  const auto truth = read_frame(path);
  if (!truth.ok()) throw UsageError("--truth: " + truth.error());
  const imaging::Image& image = truth.value().dn;
  if (image.channel_count() != 1 || image.channels[0].width != width ||
      image.channels[0].height != height)
    throw UsageError("--truth '" + path + "' must be a grey image of " + std::to_string(width) +
                     "x" + std::to_string(height) + " pixels, like the input");
  imaging::Plane plane = image.channels[0];
  const float full_scale = static_cast<float>((1 << truth.value().container_bits) - 1);
  for (float& v : plane.pixels) v /= full_scale;
  return plane;
}

/// Solves the 3x3 system m * x = b by Cramer's rule; false if m is singular.
bool solve3(const std::vector<double>& m, const std::vector<double>& b, std::vector<double>& x) {
  auto det = [](const double* a) {
    return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
           a[2] * (a[3] * a[7] - a[4] * a[6]);
  };
  const double d = det(m.data());
  double scale = 0;
  for (double v : m) scale = std::max(scale, std::abs(v));
  if (std::abs(d) <= 1e-9 * scale * scale * scale) return false;
  x.assign(3, 0.0);
  for (int col = 0; col < 3; ++col) {
    std::vector<double> a = m;
    for (int row = 0; row < 3; ++row)
      a[static_cast<std::size_t>(row * 3 + col)] = b[static_cast<std::size_t>(row)];
    x[static_cast<std::size_t>(col)] = det(a.data()) / d;
  }
  return true;
}

imaging::CaptureModel model_from_flags(const DeblurFlags& f, const LoadedFrame& frame) {
  if (f.code.empty() || f.blur < 0)
    throw UsageError("give --descriptor FILE, or --code and --blur");
  imaging::CaptureModel m;
  m.code = parse_code_argument(f.code, 0, false);
  const int channels = frame.dn.channel_count();
  if (m.code.leds() == 1 && channels != 1)
    throw UsageError("a one-LED code (plain flutter shutter) needs a grey frame; '" + f.input +
                     "' is RGB");
  if (m.code.leds() > 1 && channels != 3)
    throw UsageError("a code of " + std::to_string(m.code.leds()) + " LEDs needs an RGB frame; '" +
                     f.input + "' is grey");
  m.channels = channels;
  m.leds = channels;
  m.crosstalk =
      channels == 1 ? std::vector<double>{1.0} : std::vector<double>{1, 0, 0, 0, 1, 0, 0, 0, 1};
  if (!f.crosstalk.empty()) {
    const auto matrix = parse_crosstalk(f.crosstalk);
    if (matrix.channels != channels || matrix.leds != channels)
      throw UsageError("--crosstalk must be " + std::to_string(channels) + "x" +
                       std::to_string(channels));
    m.crosstalk = matrix.gain;
  }
  m.blur_px = f.blur;
  if (!imaging::parse_direction(f.direction, m.direction))
    throw UsageError("--direction must be +x, -x, +y or -y");
  m.black_level = f.black_level;
  m.gain = f.gain;
  m.read_noise = f.read_noise;
  m.bit_depth = frame.container_bits;
  m.full_well = std::pow(2.0, m.bit_depth) * m.gain;
  m.ambient_electrons.assign(static_cast<std::size_t>(channels), 0.0);
  m.led_electrons.assign(static_cast<std::size_t>(m.leds), 1.0);
  if (auto problem = imaging::capture_model_problem(m); !problem.empty()) throw UsageError(problem);
  // LED strengths from the frame: channel whites W = M (I * n), solved for I.
  const auto white = white_levels(imaging::dn_to_electrons(frame.dn, m));
  std::vector<double> light(white);
  if (channels == 3 && !solve3(m.crosstalk, white, light))
    throw UsageError("the crosstalk matrix is singular: the channels cannot be separated");
  for (int k = 0; k < m.code.leds(); ++k) {
    const int n = m.code.on_slots(k);
    m.led_electrons[static_cast<std::size_t>(k)] =
        n > 0 ? std::max(0.0, light[static_cast<std::size_t>(k)]) / n : 0.0;
  }
  return m;
}

imaging::CaptureModel model_from_descriptor(const DeblurFlags& f, const LoadedFrame& frame) {
  const auto json = read_json(f.descriptor);
  if (!json.ok()) throw UsageError(json.error());
  auto model = imaging::from_descriptor(json.value());
  if (!model.ok()) throw UsageError("descriptor '" + f.descriptor + "': " + model.error());
  imaging::CaptureModel m = model.value();
  if (!f.code.empty()) {
    const LedCode given = parse_code_argument(f.code, m.code.leds(), false);
    if (!(given == m.code))
      throw UsageError("--code " + codes::format_code(given) +
                       " disagrees with the descriptor's code " + codes::format_code(m.code));
  }
  if (m.bayer_rggb && frame.dn.channel_count() != 1)
    throw UsageError("'" + f.input + "' has " + std::to_string(frame.dn.channel_count()) +
                     " channels but its descriptor says it is a raw Bayer mosaic (one channel)");
  if (!m.bayer_rggb && frame.dn.channel_count() != m.channels)
    throw UsageError("'" + f.input + "' has " + std::to_string(frame.dn.channel_count()) +
                     " channels but its descriptor says " + std::to_string(m.channels));
  return m;
}

void run(const DeblurFlags& f) {
  if (!f.method.empty() && f.method != "cascade" && !imaging::method_from_name(f.method))
    throw UsageError("unknown method '" + f.method +
                     "': the methods are joint-wiener, wiener-avg, rl, tv or cascade");
  if (f.edge_prior != "tv" && f.edge_prior != "l0")
    throw UsageError("--edge-prior must be tv or l0, not '" + f.edge_prior + "'");
  // The reader's options: the session's, on the whole frame unless --decode-area labels.
  reader::ReaderOptions reader_options;
  if (const auto area = reader::decode_area_from_name(f.decode_area))
    reader_options.area = *area;
  else
    throw UsageError("--decode-area must be labels or frame, not '" + f.decode_area + "'");
  std::string tries_problem;
  const auto tries = session::parse_second_pass_tries(f.tries, tries_problem);
  if (!tries) throw UsageError("--tries: " + tries_problem);
  const auto bayer_mode = imaging::bayer_mode_from_name(f.bayer_mode);
  if (!bayer_mode)
    throw UsageError("--bayer-mode must be raw or demosaic, not '" + f.bayer_mode + "'");
  if (!f.descriptor.empty() && f.blur >= 0)
    throw UsageError("give either --descriptor or --blur, not both");
  imaging::PixelModel pixel_model{};
  if (!f.pixel_model.empty() && !imaging::parse_pixel_model(f.pixel_model, pixel_model))
    throw UsageError("--pixel-model must be box-aperture, band-limited or tap-grid, not '" +
                     f.pixel_model + "'");
  auto start = std::chrono::steady_clock::now();
  const auto frame = read_frame(f.input);
  if (!frame.ok()) throw UsageError(frame.error());
  imaging::CaptureModel model = f.descriptor.empty() ? model_from_flags(f, frame.value())
                                                     : model_from_descriptor(f, frame.value());
  if (!f.pixel_model.empty()) {
    model.pixel_model = pixel_model;
    if (const auto problem = imaging::capture_model_problem(model); !problem.empty())
      throw UsageError("--pixel-model " + f.pixel_model + ": " + problem);
  }
  if (f.method == "cascade" && model.bayer_rggb)
    throw UsageError("--method cascade works on RGB frames, not raw Bayer mosaics");
  // Offline there is no line's budget: unless told otherwise, the sharpest
  // picture the frame allows. cascade: the session's per-frame path (joint
  // Wiener, then tv and the bar sums on each window; docs/session.md, the cascade).
  const std::string method_name =
      !f.method.empty() ? f.method : (model.bayer_rggb ? "tv" : "cascade");
  const bool cascade = method_name == "cascade";
  const auto method = cascade ? std::optional{imaging::Method::kJointWiener}
                              : imaging::method_from_name(method_name);
  const double read_ms = elapsed_ms(start);
  if (f.blur_tolerance_pct >= 0 && !(f.blur_tolerance_pct < 100))
    throw UsageError("--blur-tolerance must be a percentage >= 0 and < 100, not " +
                     std::to_string(f.blur_tolerance_pct));

  start = std::chrono::steady_clock::now();
  imaging::DeblurOptions options;
  options.method = *method;
  if (f.iterations > 0) options.iterations = f.iterations;
  if (f.edge_prior == "l0") options.edge_prior = imaging::EdgePrior::kL0Gradient;
  options.threads = f.threads;
  imaging::Image electrons = imaging::dn_to_electrons(frame.value().dn, model);
  if (!f.flat.empty()) {
    if (model.bayer_rggb) throw UsageError("--flat works on RGB frames, not raw Bayer mosaics");
    const auto json = read_json(f.flat);
    if (!json.ok()) throw UsageError(json.error());
    const auto flat = imaging::flat_field_from_json(json.value());
    if (!flat.ok()) throw UsageError("flat field '" + f.flat + "': " + flat.error());
    if (auto error = imaging::apply_flat_field(electrons, flat.value()); !error.empty())
      throw UsageError("flat field '" + f.flat + "': " + error);
  }
  // The blur refined on the frame within the tolerance (RGB frames of a multi-LED code).
  const double tolerance_pct =
      f.blur_tolerance_pct >= 0 ? f.blur_tolerance_pct : (model.code.leds() >= 2 ? 10.0 : 0.0);
  nlohmann::json motion;
  start = std::chrono::steady_clock::now();
  // RGB frames: turned once into the motion frame, where the blur is refined
  // (multi-LED codes) and the frame deblurred; Bayer mosaics are split in their own geometry.
  auto motion_frame = model.bayer_rggb
                          ? Result<imaging::MotionFrame, std::string>::success({})
                          : imaging::MotionFrame::make(std::move(electrons), model.direction);
  if (!motion_frame.ok()) throw UsageError("'" + f.input + "': " + motion_frame.error());
  // (A blur that cannot fit the frame is left to deblur, which refuses it by name.)
  if (tolerance_pct > 0 && !model.bayer_rggb && model.code.leds() >= 2 &&
      imaging::refinement_fits(model, tolerance_pct / 100, motion_frame.value().along())) {
    imaging::MotionRefinementOptions refine;
    refine.tolerance = tolerance_pct / 100;
    const auto refined = imaging::refine_motion(motion_frame.value(), model, refine);
    if (!refined.ok()) throw UsageError("'" + f.input + "': refining the blur: " + refined.error());
    const auto& r = refined.value();
    motion = {{"given_blur_px", model.blur_px},
              {"tolerance_pct", tolerance_pct},
              {"edges", r.edges},
              {"residual_per_sample", r.residual_per_sample}};
    if (r.edges) {
      motion["refined_blur_px"] = r.blur_px;
      motion["standard_error_px"] = r.standard_error_px;
      motion["speed_ratio"] = r.speed_ratio;
      if (r.wandering) motion["block_offsets_px"] = r.block_offsets_px;
      motion["outside_tolerance"] = r.outside_tolerance;
    }
    const bool used = imaging::refinement_usable(r);
    motion["used"] = used;
    if (used) model = imaging::with_refined_motion(std::move(model), r);
  }
  const double refine_ms = elapsed_ms(start);
  start = std::chrono::steady_clock::now();
  // The latent in the camera's orientation, and in the motion frame (made there, turned back once).
  imaging::DeblurResult deblurred;
  imaging::Plane motion_latent;
  if (model.bayer_rggb) {
    auto r = imaging::deblur_bayer(electrons.channels[0], model, options, *bayer_mode);
    if (!r.ok()) throw UsageError("'" + f.input + "': " + r.error());
    motion_latent = std::move(r.value().motion_latent);
    deblurred = std::move(r.value());
  } else {
    auto r = imaging::deblur(motion_frame.value(), model, options);
    if (!r.ok()) throw UsageError("'" + f.input + "': " + r.error());
    deblurred = std::move(r.value());
    motion_latent = std::move(deblurred.latent);
    deblurred.latent = motion_frame.value().to_camera(motion_latent);
  }
  const double deblur_ms = elapsed_ms(start);

  // The cascade: the first read, then each window it read nothing in deblurred
  // again and read (every window: no line's budget offline), pasted into the latents.
  std::optional<reader::BarcodeReadout> cascade_readout;
  nlohmann::json second_pass;
  double cascade_ms = 0;
  if (cascade) {
    start = std::chrono::steady_clock::now();
    // Beyond the windows the picture is tv's on the whole frame: offline there
    // is time for it, and joint Wiener's noise on the belt costs the picture
    // about 10 dB of PSNR.
    imaging::DeblurOptions whole = options;
    whole.method = imaging::Method::kTotalVariation;
    auto backdrop = imaging::deblur(motion_frame.value(), model, whole);
    if (!backdrop.ok()) throw UsageError("'" + f.input + "': " + backdrop.error());
    cascade_readout =
        session::read_with_cascade({motion_frame.value(), model, motion_latent, &deblurred.latent},
                                   backdrop.value().latent, reader_options, *tries, second_pass);
    cascade_ms = elapsed_ms(start);
  }

  start = std::chrono::steady_clock::now();
  imaging::Image out;
  out.channels.push_back(deblurred.latent);
  for (float& v : out.channels[0].pixels) v = std::clamp(v, 0.0f, 1.0f) * 65535.0f;
  if (auto error = write_png16(f.output, out); !error.empty()) throw RuntimeFailure(error);
  const double write_ms = elapsed_ms(start);

  double psnr_db = 0, ssim_index = 0;
  if (!f.truth.empty()) {
    const imaging::Plane& latent = deblurred.latent;
    const imaging::Plane truth = read_truth(f.truth, latent.width, latent.height);
    const auto region =
        imaging::scored_region(latent.width, latent.height, model.blur_px, model.direction);
    psnr_db = imaging::psnr(truth, latent, region);
    ssim_index = imaging::ssim(truth, latent, region);
  }

  reader::BarcodeReadout decoded;
  double decode_ms = 0;
  if (f.decode && cascade_readout) {
    decoded = std::move(*cascade_readout);
  } else if (f.decode) {
    start = std::chrono::steady_clock::now();
    const std::vector<reader::LabelRegion> paper =
        reader_options.area == reader::DecodeArea::kLabels
            ? reader::regions_to_read(reader::find_paper_runs(motion_latent),
                                      reader::find_code_regions(motion_latent))
            : std::vector<reader::LabelRegion>{};
    decoded = reader::read_codes(deblurred.latent, paper, model.direction, reader_options).readout;
    decode_ms = elapsed_ms(start);
  }
  if (f.json) {
    nlohmann::json report = {
        {"input", f.input},
        {"output", f.output},
        {"method", method_name},
        {"pixel_model", imaging::pixel_model_name(model.pixel_model)},
        {"timings_ms",
         {{"read", read_ms}, {"refine", refine_ms}, {"deblur", deblur_ms}, {"write", write_ms}}},
        {"noise_variance_e2", deblurred.noise_variance}};
    if (!motion.is_null()) report["motion"] = motion;
    if (cascade) {
      report["timings_ms"]["cascade"] = cascade_ms;
      report["second_pass"] = second_pass;
    }
    if (f.decode) {
      if (!cascade) report["timings_ms"]["decode"] = decode_ms;  // the cascade's is in "cascade"
      report["decoded"] = reader::code_texts(decoded);
      // Each value with the evidence that backs it: the decoder, and the latent it was read on.
      nlohmann::json codes = nlohmann::json::array();
      for (const reader::DecodedCode& code : decoded.codes)
        codes.push_back(session::value_json(code));
      report["codes"] = std::move(codes);
      nlohmann::json unconfirmed = nlohmann::json::array();
      for (const reader::DecodedCode& code : decoded.unconfirmed)
        unconfirmed.push_back(session::value_json(code));
      report["unconfirmed"] = std::move(unconfirmed);
    }
    if (!f.truth.empty()) report["truth"] = {{"psnr_db", psnr_db}, {"ssim", ssim_index}};
    std::cout << report.dump() << "\n";
    return;
  }
  std::cout << "wrote " << f.output << " (" << method_name << ", " << static_cast<int>(deblur_ms)
            << " ms)\n";
  if (!motion.is_null()) {
    if (!motion["edges"].get<bool>())
      std::cout << "blur " << motion["given_blur_px"].get<double>()
                << " px used as given: the frame has no edges along the motion to refine it\n";
    else
      std::cout << "blur " << motion["given_blur_px"].get<double>() << " px refined to "
                << motion["refined_blur_px"].get<double>() << " +- "
                << motion["standard_error_px"].get<double>() << " px"
                << (motion["used"].get<bool>() ? ""
                    : motion["outside_tolerance"].get<bool>()
                        ? " (outside the tolerance: not used, "
                          "check the blur or widen --blur-tolerance)"
                        : " (the grey model does not fit the "
                          "frame: not used)")
                << "\n";
  }
  if (cascade) {
    std::size_t windows_read = 0;
    for (const auto& window : second_pass["windows"]) windows_read += !window["read"].empty();
    // Offline every label and code region is deblurred again, read or not.
    std::cout << "cascade: " << second_pass["windows"].size()
              << " label or code window(s) deblurred again by tv, " << windows_read
              << " of them read a code the first read had not; tv's whole frame beyond them ("
              << static_cast<int>(cascade_ms) << " ms)\n";
  }
  if (!f.truth.empty())
    std::cout << "against " << f.truth << ": PSNR " << psnr_db << " dB, SSIM " << ssim_index
              << "\n";
  if (f.decode) {
    if (decoded.codes.empty()) std::cout << "no barcode decoded\n";
    for (const auto& text : reader::code_texts(decoded)) std::cout << "decoded: " << text << "\n";
  }
}

}  // namespace

void add_deblur(CLI::App& app) {
  auto f = std::make_shared<DeblurFlags>();
  CLI::App* command =
      app.add_subcommand("deblur", "Deblur a coded-light frame into one sharp grey image");
  command
      ->add_option("input", f->input,
                   "8- or 16-bit RGB (or grey: one-LED code, or a raw Bayer mosaic with its "
                   "descriptor) PNG or TIFF")
      ->required();
  command->add_option("--descriptor", f->descriptor, "the frame's capture descriptor (JSON)");
  command->add_option("--code", f->code, "LED code (without a descriptor)");
  command->add_option("--blur", f->blur,
                      "motion during the exposure, pixels (without a descriptor)");
  command
      ->add_option("--blur-tolerance", f->blur_tolerance_pct,
                   "refine the blur on the frame within +-PCT% of --blur or the descriptor's "
                   "blur_px (0: use it exactly; default 10 for codes of two or more LEDs)")
      ->check(CLI::Range(0.0, 1e9));
  command->add_option("--direction", f->direction, "+x, -x, +y or -y")->capture_default_str();
  command->add_option("--pixel-model", f->pixel_model,
                      "box-aperture (default), band-limited (frames of a band-limited scene) or "
                      "tap-grid; overrides the descriptor's");
  command->add_option("--crosstalk", f->crosstalk, "LED-to-channel matrix \"m00,m01,m02;m10,...\"");
  command->add_option("--black-level", f->black_level, "DN")->capture_default_str();
  command->add_option("--gain", f->gain, "e- per DN")->capture_default_str();
  command->add_option("--read-noise", f->read_noise, "e- rms")->capture_default_str();
  command->add_option("--method", f->method,
                      "cascade (default: the session's path, joint Wiener on the frame, then tv "
                      "and the bar sums on every label and code region, tv's whole frame beyond "
                      "them; the sharpest picture and the most codes read), tv (the default for "
                      "raw Bayer mosaics), joint-wiener "
                      "(the fast one a line runs on every frame), wiener-avg or rl");
  command
      ->add_option("--iterations", f->iterations,
                   "rl iterations (default " + std::to_string(imaging::kRichardsonLucyIterations) +
                       "), tv iterations (default " +
                       std::to_string(imaging::kTotalVariationIterations) + ")")
      ->check(CLI::Range(1, 10000));
  command
      ->add_option("--edge-prior", f->edge_prior,
                   "tv method's prior: tv (|gradient|) or l0 (count of edges: sharper on "
                   "axis-aligned two-tone print, worse on rotated labels)")
      ->capture_default_str();
  command
      ->add_option("--bayer-mode", f->bayer_mode,
                   "raw Bayer frames: raw (deblur the four colour planes) or demosaic (bilinear "
                   "demosaic, then deblur as RGB)")
      ->capture_default_str();
  command->add_option("--threads", f->threads, "threads")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  command->add_option("-o,--output", f->output, "16-bit grey PNG to write")->required();
  command->add_flag("--decode", f->decode, "also decode the barcodes on the result");
  command
      ->add_option("--decode-area", f->decode_area,
                   "with --decode: frame (the whole result) or labels (the label paper and "
                   "the regions that look like print, as a session reads by default)")
      ->capture_default_str();
  command
      ->add_option("--tries", f->tries,
                   std::string("the cascade's second-pass tries beyond tv on each window, "
                               "comma-separated: ") +
                       session::kSecondPassTryNames + ", or none, or all")
      ->capture_default_str();
  command->add_option("--flat", f->flat,
                      "flat-field file (`calibrate flat`): corrects light that varies across the "
                      "field of view before deblurring");
  command->add_option(
      "--truth", f->truth,
      "ground truth to score against (16-bit grey PNG of reflectance, as "
      "`simulate` writes): prints PSNR and SSIM over the scoring region of docs/conventions.md");
  command->add_flag("--json", f->json, "print one JSON object (method, timings, decoded values)");
  command->callback([f] { run(*f); });
}

}  // namespace flutterscan::app
