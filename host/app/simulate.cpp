// `flutterscan simulate --scene code128:TEXT --code DIGITS --blur 52 --electrons 3000 -o frame.png`
// writes the frame (16-bit PNG), its capture descriptor (frame.json) and the
// ground truth (frame.truth.png, reflectance x 65535).
// `--scene photo:PATH [--rotate DEG]` takes a photo of a real label as the
// object (sim/photo_scene.hpp): its colour channels are the reflectance under
// the red, green and blue LEDs, and the truth is their fusion (sim::fuse_bands).

#include <cmath>
#include <iostream>
#include <memory>

#include "app/cli_errors.hpp"
#include "app/code_arguments.hpp"
#include "app/commands.hpp"
#include "app/image_io.hpp"
#include "imaging/capture_descriptor.hpp"
#include "imaging/motion_frame.hpp"
#include "sim/colour_scene.hpp"
#include "sim/forward_model.hpp"
#include "sim/photo_scene.hpp"
#include "sim/pixel_integration.hpp"
#include "sim/scene.hpp"
#include "sim/timeline_forward.hpp"

namespace flutterscan::app {
namespace {

struct SimulateOptions {
  std::string scene;
  std::string code;
  int leds = 0;  ///< 0: from the code (0s and 1s: one LED, else three)
  double blur = 52;
  std::string direction = "+x";
  double electrons = 3000;
  double cap = 3;
  std::string crosstalk;
  double ambient = 0;
  double read_noise = 4;
  double full_well = 12000;
  int bit_depth = 12;
  double black_level = 64;
  double gain = 0;  ///< 0: full well maps to full scale
  bool bayer = false;
  std::string encoding = "linear";
  int width = 640;
  int height = 360;
  bool width_given = false;  ///< photo scenes size themselves unless told
  bool height_given = false;
  double rotate = 0;  ///< photo scenes: degrees, anticlockwise
  double module = 3;
  std::uint64_t seed = 1;
  std::string output;
};

void require(bool ok, const std::string& message) {
  if (!ok) throw UsageError(message);
}

imaging::CaptureModel capture_model(const SimulateOptions& o) {
  imaging::CaptureModel m;
  const LedCode code = parse_code_argument(o.code, o.leds, false);
  require(code.leds() == 1 || code.leds() == 3,
          "the simulated cameras are mono (one LED) or RGB (three LEDs), not " +
              std::to_string(code.leds()) + " LEDs");
  require(std::isfinite(o.electrons) && o.electrons >= 0,
          "--electrons must be a finite number >= 0 (0: a dark frame)");
  require(std::isfinite(o.cap) && o.cap > 0, "--cap must be a finite number > 0");
  require(std::isfinite(o.ambient) && o.ambient >= 0, "--ambient must be a finite number >= 0");
  m.code = code;
  m.leds = code.leds() == 1 ? 1 : 3;
  m.channels = code.leds() == 1 ? 1 : 3;
  m.blur_px = o.blur;
  require(imaging::parse_direction(o.direction, m.direction),
          "--direction must be +x, -x, +y or -y");
  if (m.channels == 1) {
    m.crosstalk = {1.0};
  } else if (!o.crosstalk.empty()) {
    const auto matrix = parse_crosstalk(o.crosstalk);
    require(matrix.channels == 3 && matrix.leds == 3, "--crosstalk must be 3x3 for an RGB capture");
    m.crosstalk = matrix.gain;
  }
  const auto per_bit = imaging::budgeted_led_electrons(code, o.electrons, o.cap);
  m.led_electrons.assign(static_cast<std::size_t>(m.leds), 0.0);
  for (int k = 0; k < code.leds(); ++k)
    m.led_electrons[static_cast<std::size_t>(m.led_of_bit[static_cast<std::size_t>(k)])] =
        per_bit[static_cast<std::size_t>(k)];
  m.ambient_electrons.assign(static_cast<std::size_t>(m.channels), o.ambient);
  m.read_noise = o.read_noise;
  m.full_well = o.full_well;
  m.bit_depth = o.bit_depth;
  m.black_level = o.black_level;
  m.gain = o.gain > 0 ? o.gain : o.full_well / (std::pow(2.0, o.bit_depth) - 1.0);
  m.bayer_rggb = o.bayer;
  if (o.encoding == "srgb") m.encoding = imaging::Encoding::kSrgb;
  if (auto problem = imaging::capture_model_problem(m); !problem.empty()) throw UsageError(problem);
  require(!m.bayer_rggb || m.channels == 3, "--bayer needs a code of three LEDs");
  return m;
}

/// A photo scene's frame where --width or --height do not say: the turned
/// photo with kMinBeltPx of belt across the motion and its blur plus kMinBeltPx
/// along it (the whole smear in view, belt before and after).
void size_photo_frame(const SimulateOptions& o, const imaging::CaptureModel& model,
                      sim::SceneSpec& spec) {
  const auto least = sim::photo_frame_size(spec);
  if (!least.ok()) throw UsageError("--scene: " + least.error());
  const int smear = 2 * static_cast<int>(std::ceil(model.blur_px));
  const bool along_x = imaging::moves_along_x(model.direction);
  if (!o.width_given) spec.width = least.value().first + (along_x ? smear : 0);
  if (!o.height_given) spec.height = least.value().second + (along_x ? 0 : smear);
}

/// The scene's expected electrons and its truth (the sharp grey view), rendered
/// finer than the pixels so that it moves continuously within each pixel. A
/// photo scene seen by an RGB camera under three LEDs is a colour object.
std::pair<imaging::Image, imaging::Plane> render(const sim::SceneSpec& spec,
                                                 const imaging::CaptureModel& model) {
  constexpr int k = sim::kSimSupersample;
  if (spec.kind == sim::SceneKind::kPhoto && model.leds == 3) {
    auto bands = sim::render_photo_bands(spec, k);
    if (!bands.ok()) throw UsageError("--scene: " + bands.error());
    auto expected = sim::expected_colour_electrons(bands.value(), model, k);
    if (!expected.ok()) throw UsageError("--scene: " + expected.error());
    return {std::move(expected.value()), sim::bin_pixels(sim::fuse_bands(bands.value()), k)};
  }
  const auto fine = sim::render_scene(spec, k);
  if (!fine.ok()) throw UsageError("--scene: " + fine.error());
  return {sim::expected_electrons(fine.value(), model, k), sim::bin_pixels(fine.value(), k)};
}

/// What the descriptor says of a photo scene: the photo, its turn, where it
/// lies and the reflectance its samples were scaled into.
nlohmann::json photo_record(const sim::SceneSpec& spec, const imaging::CaptureModel& model) {
  const auto layout = sim::photo_layout(spec);
  if (!layout.ok()) throw UsageError("--scene: " + layout.error());
  const sim::PhotoLayout& l = layout.value();
  return {{"path", spec.content},
          {"size", {l.photo_width, l.photo_height}},
          {"bands", l.grey            ? "grey (one band for all three LEDs)"
                    : model.leds == 3 ? "red, green, blue (LEDs 0, 1, 2)"
                                      : "fused to grey (one LED)"},
          {"decoding", "sRGB to linear"},
          {"reflectance", {sim::kPhotoBlack, sim::kPhotoWhite}},
          {"rotate_deg", spec.rotate_deg},
          {"centre_px", {l.centre_x, l.centre_y}},
          {"belt", spec.belt}};
}

void run(const SimulateOptions& o) {
  const imaging::CaptureModel model = capture_model(o);
  auto spec = sim::parse_scene(o.scene);
  if (!spec.ok()) throw UsageError("--scene: " + spec.error());
  const bool photo = spec.value().kind == sim::SceneKind::kPhoto;
  require(photo || o.rotate == 0, "--rotate turns photo scenes only (--scene photo:PATH)");
  require(std::isfinite(o.rotate) && std::abs(o.rotate) <= 360,
          "--rotate must be a number of degrees from -360 to 360");
  spec.value().width = o.width;
  spec.value().height = o.height;
  spec.value().module_px = o.module;
  spec.value().rotate_deg = o.rotate;
  if (photo) size_photo_frame(o, model, spec.value());
  const int width = spec.value().width, height = spec.value().height;
  require(model.blur_px < imaging::length_along_motion(model.direction, width, height),
          "--blur must be shorter than the image along the motion");
  const auto [expected, truth] = render(spec.value(), model);
  const auto frame = sim::record_frame(expected, model, o.seed);
  const std::string descriptor_path = sibling_path(o.output, "", ".json");
  const std::string truth_path = sibling_path(o.output, ".truth", ".png");
  imaging::Image truth_image;
  truth_image.channels.push_back(truth);
  for (float& v : truth_image.channels[0].pixels) v *= 65535.0f;
  nlohmann::json descriptor = imaging::to_descriptor(model);
  descriptor["simulation"] = {{"scene", o.scene},
                              {"seed", o.seed},
                              {"electrons", o.electrons},
                              {"cap", o.cap},
                              {"supersample", sim::kSimSupersample},
                              {"truth", truth_path}};
  if (photo) descriptor["simulation"]["photo"] = photo_record(spec.value(), model);
  for (const auto& error :
       {write_png16(o.output, frame), write_text(descriptor_path, descriptor.dump(2) + "\n"),
        write_png16(truth_path, truth_image)})
    if (!error.empty()) throw RuntimeFailure(error);
  std::cout << "wrote " << o.output << ", " << descriptor_path << ", " << truth_path << "\n";
}

}  // namespace

void add_simulate(CLI::App& app) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* command =
      app.add_subcommand("simulate", "Render a coded-light frame of a label on a moving belt");
  command
      ->add_option(
          "--scene", o->scene,
          "code128:TEXT, ean13:DIGITS, qr:TEXT, datamatrix:TEXT, text:WORDS, image:PATH, "
          "photo:PATH (a photo of a real label on the belt, its colours the reflectance under "
          "the LEDs) or flat:REFLECTANCE (a calibration target)")
      ->required();
  command->add_option("--code", o->code, "LED code: digits or a library name")->required();
  command
      ->add_option("--leds", o->leds,
                   "LEDs the code drives, 1 (mono camera) or 3 (RGB); default: 1 for codes of 0s "
                   "and 1s, else 3 (give 3 for one LED alone on an RGB camera: 1111...)")
      ->check(CLI::IsMember({1, 3}));
  command->add_option("--blur", o->blur, "motion during the exposure, pixels")
      ->capture_default_str();
  command->add_option("--direction", o->direction, "+x, -x, +y or -y")->capture_default_str();
  command
      ->add_option("--electrons", o->electrons,
                   "light level E: e- per channel of white under rect-white")
      ->capture_default_str();
  command->add_option("--cap", o->cap, "overdrive cap c")->capture_default_str();
  command->add_option("--crosstalk", o->crosstalk,
                      "3x3 LED-to-channel matrix \"m00,m01,m02;m10,...\"");
  command->add_option("--ambient", o->ambient, "ambient light, e- per channel per exposure")
      ->capture_default_str();
  command->add_option("--read-noise", o->read_noise, "e- rms")->capture_default_str();
  command->add_option("--full-well", o->full_well, "e-")->capture_default_str();
  command->add_option("--bit-depth", o->bit_depth, "bits per sample")
      ->check(CLI::Range(8, 16))
      ->capture_default_str();
  command->add_option("--black-level", o->black_level, "DN")->capture_default_str();
  command->add_option("--gain", o->gain, "e- per DN (default: full well at full scale)");
  command->add_flag("--bayer", o->bayer, "write a raw RGGB mosaic instead of RGB");
  command->add_option("--encoding", o->encoding, "linear or srgb")
      ->check(CLI::IsMember({"linear", "srgb"}))
      ->capture_default_str();
  CLI::Option* width =
      command->add_option("--width", o->width, "frame width (photo scenes: sized to the photo)")
          ->check(CLI::Range(16, 16384))
          ->capture_default_str();
  CLI::Option* height =
      command->add_option("--height", o->height, "frame height (photo scenes: sized to the photo)")
          ->check(CLI::Range(16, 16384))
          ->capture_default_str();
  command->add_option("--rotate", o->rotate,
                      "photo scenes: turn the photo by DEG degrees, anticlockwise on the image");
  command->add_option("--module", o->module, "barcode module width, pixels")
      ->check(CLI::Range(0.5, 100.0))
      ->capture_default_str();
  command->add_option("--seed", o->seed, "noise seed")->capture_default_str();
  command->add_option("-o,--output", o->output, "frame PNG to write")->required();
  command->callback([o, width, height] {
    o->width_given = width->count() > 0;
    o->height_given = height->count() > 0;
    run(*o);
  });
}

}  // namespace flutterscan::app
