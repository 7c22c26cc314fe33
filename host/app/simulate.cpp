// `flutterscan simulate --scene code128:TEXT --code DIGITS --blur 52 --electrons 3000 -o frame.png`
// writes the frame (16-bit PNG), its capture descriptor (frame.json) and the
// ground truth (frame.truth.png, reflectance x 65535).

#include <cmath>
#include <iostream>
#include <memory>

#include "app/cli_errors.hpp"
#include "app/code_arguments.hpp"
#include "app/commands.hpp"
#include "app/image_io.hpp"
#include "imaging/capture_descriptor.hpp"
#include "imaging/motion_frame.hpp"
#include "sim/forward_model.hpp"
#include "sim/pixel_integration.hpp"
#include "sim/scene.hpp"

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

void run(const SimulateOptions& o) {
  const imaging::CaptureModel model = capture_model(o);
  auto spec = sim::parse_scene(o.scene);
  if (!spec.ok()) throw UsageError("--scene: " + spec.error());
  spec.value().width = o.width;
  spec.value().height = o.height;
  spec.value().module_px = o.module;
  require(model.blur_px < imaging::length_along_motion(model.direction, o.width, o.height),
          "--blur must be shorter than the image along the motion");
  // The scene is rendered finer than the pixels so that it moves continuously
  // within each pixel; the truth is what a sharp capture of it records.
  const auto fine = sim::render_scene(spec.value(), sim::kSimSupersample);
  if (!fine.ok()) throw UsageError("--scene: " + fine.error());
  const imaging::Plane truth = sim::bin_pixels(fine.value(), sim::kSimSupersample);

  const auto frame = sim::record_frame(
      sim::expected_electrons(fine.value(), model, sim::kSimSupersample), model, o.seed);
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
          "code128:TEXT, ean13:DIGITS, qr:TEXT, datamatrix:TEXT, text:WORDS, image:PATH or "
          "flat:REFLECTANCE (a calibration target)")
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
  command->add_option("--width", o->width, "frame width")
      ->check(CLI::Range(16, 16384))
      ->capture_default_str();
  command->add_option("--height", o->height, "frame height")
      ->check(CLI::Range(16, 16384))
      ->capture_default_str();
  command->add_option("--module", o->module, "barcode module width, pixels")
      ->check(CLI::Range(0.5, 100.0))
      ->capture_default_str();
  command->add_option("--seed", o->seed, "noise seed")->capture_default_str();
  command->add_option("-o,--output", o->output, "frame PNG to write")->required();
  command->callback([o] { run(*o); });
}

}  // namespace flutterscan::app
