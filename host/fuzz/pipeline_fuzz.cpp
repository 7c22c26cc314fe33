// libFuzzer target: the session's per-frame pipeline (host/session/session.cpp's
// process) with fuzzed capture models on a small frame: the exposure event
// (encoder counts, slot time), the optics (px_per_count or the nominal blur
// without an encoder, direction, crosstalk, electrons, cap, noise, full well,
// black level, gain, bit depth), the code (a one-of-3 code of 3..52 slots) and
// the processing (method, model choice, blur checks, rolling shutter) go
// through check_config, the blur range check, frame_model, frame_to_electrons
// and deblur_fitting_model, on an RGB16 or mono16 frame of 16..48 x 12..16 px
// with a few label-like bars.
// Oracles: an accepted config's frame either is flagged blur-out-of-range, or
// gets a model, or is refused with a message; a deblurred frame is finite and of
// the frame's size; a frame whose blur is in range never fails for a blur that
// does not fit.

#include <cmath>
#include <utility>

#include "capture/frame_pixels.hpp"
#include "fuzz_support.hpp"
#include "imaging/capture_descriptor.hpp"
#include "imaging/motion_frame.hpp"
#include "session/frame_model.hpp"
#include "session/model_fit.hpp"
#include "session/session_config.hpp"

using namespace flutterscan;

namespace {
imaging::Method options_method(const session::SessionConfig& config) {
  return config.processing.method;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 4096) return 0;
  fuzz::Bytes in(data, size);
  session::SessionConfig config;
  auto& o = config.optics;
  o.encoder = in.u8() % 4 != 0;
  o.px_per_count = in.number(0.01, 4);
  o.nominal_blur_px = in.number(0, 40);
  static constexpr const char* kDirections[] = {"+x", "-x", "+y", "-y"};
  o.direction = kDirections[in.u8() % 4];
  for (double& v : o.crosstalk) v = in.u8() < 240 ? in.number(0, 1) : in.number(-1, 1e6);
  o.electrons = in.number(10, 20000);
  o.cap = in.number(1, 5);
  o.read_noise_e = in.number(0, 20);
  o.full_well_e = in.number(1000, 40000);
  o.black_level_dn = in.number(0, 200);
  o.gain_e_per_dn = in.u8() % 2 == 0 ? 0 : in.number(0.01, 20);
  o.bit_depth = 8 + static_cast<int>(in.u8() % 9);
  o.line_time_us = in.u8() % 4 == 0 ? in.number(0, 50) : 0;
  // A one-of-3 code of 3..52 slots.
  const int slots = 3 + static_cast<int>(in.u8() % 50);
  std::string digits;  // one LED per slot: masks 1, 2, 4
  for (int s = 0; s < slots; ++s) digits += "124"[in.u8() % 3];
  config.controller.code = digits;
  static constexpr imaging::Method kMethods[] = {
      imaging::Method::kJointWiener, imaging::Method::kWienerAverage,
      imaging::Method::kRichardsonLucy, imaging::Method::kTotalVariation};
  config.processing.method = kMethods[in.u8() % 4];
  config.processing.choose_model = in.flag();
  config.processing.blur_check_every = in.u8() % 3;
  if (const std::string problem = session::check_config(config); !problem.empty()) {
    fuzz::trace("config refused: " + problem);
    FUZZ_CHECK(problem.find('.') != std::string::npos, "a refusal naming no key: " + problem);
    return 0;
  }

  session::ExposureRecord event;
  event.frame_counter = in.u32();
  event.encoder_delta = static_cast<std::int32_t>(in.u8() < 230 ? in.u8() % 80 - 20 : in.u32());
  event.slot_time_us = 100;
  event.slot_count = static_cast<std::uint16_t>(config.controller.parsed_code.length());
  capture::Frame frame;
  const bool mono = in.u8() % 4 == 0;
  frame.format.pixel_format = mono ? capture::PixelFormat::kMono16 : capture::PixelFormat::kRgb16;
  // A few sizes only: FFT plans are made once per row length, and cached.
  static constexpr int kWidths[] = {16, 24, 32, 48}, kHeights[] = {12, 16};
  frame.format.width = kWidths[in.u8() % 4];
  frame.format.height = kHeights[in.u8() % 2];
  frame.format.bit_depth = o.bit_depth;
  const int samples = mono ? 1 : 3;
  frame.data.resize(static_cast<std::size_t>(frame.format.width) * frame.format.height * samples *
                    2);
  const int top = (1 << o.bit_depth) - 1;
  for (int y = 0; y < frame.format.height; ++y)
    for (int x = 0; x < frame.format.width; ++x)
      for (int c = 0; c < samples; ++c) {
        const int value = ((x / 5 + c) % 3 == 0 ? top / 8 : top / 2) + (y % 7) * 3;
        const std::size_t at =
            2 * ((static_cast<std::size_t>(y) * frame.format.width + x) * samples + c);
        frame.data[at] = static_cast<std::uint8_t>(std::min(value, top) & 0xFF);
        frame.data[at + 1] = static_cast<std::uint8_t>(std::min(value, top) >> 8);
      }

  const std::string out_of_range = session::blur_out_of_range(event, o, frame.format);
  if (!out_of_range.empty()) {
    fuzz::trace(out_of_range);
    FUZZ_CHECK(out_of_range.find("blur-out-of-range") != std::string::npos, out_of_range);
    return 0;  // flagged, the session goes on
  }
  auto model = session::frame_model(event, config.controller.parsed_code, config, frame.format);
  if (!model.ok()) {
    fuzz::trace("model refused: " + model.error());
    FUZZ_CHECK(!model.error().empty(), "a model refused without a message");
    return 0;
  }
  // (Built only when tracing: the descriptor's JSON dump cost every execution.)
  if (fuzz::tracing())
    fuzz::trace("model " + imaging::to_descriptor(model.value()).dump() + ", method " +
                imaging::method_name(options_method(config)) + ", choose " +
                std::to_string(config.processing.choose_model) + ", line time " +
                std::to_string(o.line_time_us) + ", " + std::to_string(frame.format.width) + "x" +
                std::to_string(frame.format.height));
  auto electrons = capture::frame_to_electrons(frame, model.value());
  if (!electrons.ok()) {
    fuzz::trace("conversion refused: " + electrons.error());
    FUZZ_CHECK(!electrons.error().empty(), "a conversion refused without a message");
    return 0;
  }
  imaging::DeblurOptions options;
  options.method = config.processing.method;
  options.threads = 1;
  options.iterations = 3;
  session::ModelFitConfig fit;
  fit.encoder = o.encoder;
  fit.choose_latent = config.processing.choose_model;
  fit.line_time_us = o.line_time_us;
  fit.slot_time_us = event.slot_time_us;
  fit.blur_check_every = config.processing.blur_check_every;
  fit.fallback_blur_px = o.nominal_blur_px;
  const auto motion = imaging::MotionFrame::make(std::move(electrons.value().electrons),
                                                 model.value().direction, electrons.value().values);
  if (!motion.ok()) {
    fuzz::trace("frame refused: " + motion.error());
    FUZZ_CHECK(!motion.error().empty(), "a frame refused without a message");
    return 0;
  }
  auto fitted = session::deblur_fitting_model(electrons.value().saturated_share, motion.value(),
                                              model.value(), options, fit, in.u8());
  if (!fitted.ok()) {
    fuzz::trace("deblur refused: " + fitted.error());
    FUZZ_CHECK(!fitted.error().empty(), "a deblur refused without a message");
    FUZZ_CHECK(fitted.error().find("does not fit") == std::string::npos &&
                   fitted.error().find("not shorter than the image") == std::string::npos,
               "a blur the range check passed does not fit: " + fitted.error());
    return 0;
  }
  const imaging::Plane latent = motion.value().to_camera(fitted.value().latent);
  fuzz::trace("deblurred, blur " + std::to_string(model.value().blur_px));
  FUZZ_CHECK(latent.width == frame.format.width && latent.height == frame.format.height,
             "latent of another size");
  for (float v : latent.pixels) FUZZ_CHECK(std::isfinite(v), "a deblurred pixel is not finite");
  return 0;
}
