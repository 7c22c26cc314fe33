// libFuzzer target: frames as the host decodes them.
//
// Byte 0 even: the rest is a frame file (PNG or TIFF, 8 or 16 bit, grey or RGB)
// through decode_frame (host/app/image_io.hpp, what `flutterscan deblur` and the
// files camera read), then the DN to electrons conversion.
// Byte 0 odd: a camera frame: pixel format (mono8/16, rgb8, bgr8, rgb16, Bayer
// RGGB 8/16, yuyv, mjpeg), width, height (1..64), bit depth and row stride from
// the next bytes, the rest its pixel data, through frame_to_dn and
// frame_to_electrons (host/capture/frame_pixels.hpp), and for Bayer mosaics
// split_bayer_planes and demosaic_bilinear (host/imaging/bayer.hpp).
// Oracles: a refusal names the problem; a decoded frame has 1 or 3 planes of
// the declared size, values within the container's range, and finite electrons.

#include <cmath>

#include "app/image_io.hpp"
#include "capture/frame_pixels.hpp"
#include "fuzz_support.hpp"
#include "imaging/bayer.hpp"
#include "imaging/frame_conversion.hpp"

using namespace flutterscan;

namespace {

void check_finite(const imaging::Image& image, const char* what) {
  for (const auto& plane : image.channels) {
    FUZZ_CHECK(plane.pixels.size() == static_cast<std::size_t>(plane.width) * plane.height, what);
    for (float v : plane.pixels) FUZZ_CHECK(std::isfinite(v), what);
  }
}

imaging::CaptureModel model_for(int channels, int bit_depth, bool bayer) {
  imaging::CaptureModel m;
  m.channels = channels;
  m.crosstalk = channels == 1
                    ? std::vector<double>{1, 1, 1}
                    : std::vector<double>{0.9, 0.08, 0.01, 0.1, 0.85, 0.12, 0.01, 0.07, 0.88};
  m.led_electrons = {100, 100, 100};
  m.ambient_electrons.assign(static_cast<std::size_t>(channels), 0.0);
  m.bit_depth = bit_depth;
  m.black_level = 64;
  m.gain = 12000 / (std::pow(2.0, bit_depth) - 1);
  m.bayer_rggb = bayer;
  return m;
}

void fuzz_file(fuzz::Bytes& in) {
  const auto bytes = in.rest();
  auto frame = app::decode_frame(bytes, "fuzz");
  if (!frame.ok()) {
    fuzz::trace("file refused: " + frame.error());
    FUZZ_CHECK(frame.error().find("fuzz") != std::string::npos,
               "a refusal that does not name the file: " + frame.error());
    return;
  }
  const imaging::Image& dn = frame.value().dn;
  FUZZ_CHECK(dn.channel_count() == 1 || dn.channel_count() == 3, "channels");
  const double top = frame.value().container_bits == 8 ? 255 : 65535;
  for (const auto& plane : dn.channels) {
    FUZZ_CHECK(plane.width == dn.width() && plane.height == dn.height(), "plane sizes differ");
    for (float v : plane.pixels) FUZZ_CHECK(v >= 0 && v <= top, "a value beyond the container");
  }
  check_finite(imaging::dn_to_electrons(
                   dn, model_for(dn.channel_count(), frame.value().container_bits, false)),
               "electrons of a decoded file");
}

void fuzz_camera_frame(fuzz::Bytes& in) {
  capture::Frame frame;
  frame.format.pixel_format = static_cast<capture::PixelFormat>(in.u8() % 9);
  frame.format.width = static_cast<int>(in.u8() % 65);
  frame.format.height = static_cast<int>(in.u8() % 65);
  frame.format.bit_depth = static_cast<int>(in.u8() % 18);
  const std::uint8_t stride = in.u8();
  frame.format.row_bytes = stride < 200 ? 0 : stride;  // 0: packed
  frame.data = in.rest();
  using capture::PixelFormat;
  const PixelFormat f = frame.format.pixel_format;
  const bool bayer = capture::is_bayer_mosaic(f);
  const bool mono = f == PixelFormat::kMono8 || f == PixelFormat::kMono16;
  auto dn = capture::frame_to_dn(frame);
  if (!dn.ok()) {
    fuzz::trace("frame refused: " + dn.error());
    FUZZ_CHECK(!dn.error().empty(), "a refused frame without a message");
  } else {
    FUZZ_CHECK(
        dn.value().width() == frame.format.width && dn.value().height() == frame.format.height,
        "DN image of another size than the frame");
    check_finite(dn.value(), "DN");
    if (bayer && dn.value().channel_count() == 1 && frame.format.width % 2 == 0 &&
        frame.format.height % 2 == 0 && frame.format.width >= 2 && frame.format.height >= 2) {
      check_finite(imaging::split_bayer_planes(dn.value().channels[0]), "Bayer planes");
      check_finite(imaging::demosaic_bilinear(dn.value().channels[0]), "demosaic");
    }
  }
  const int depth = std::clamp(frame.format.bit_depth, 8, 16);
  const auto electrons = capture::frame_to_electrons(frame, model_for(mono ? 1 : 3, depth, bayer));
  if (!electrons.ok()) {
    FUZZ_CHECK(!electrons.error().empty(), "a refused conversion without a message");
    return;
  }
  fuzz::trace("frame converted");
  check_finite(electrons.value().electrons, "electrons");
  FUZZ_CHECK(electrons.value().saturated_share >= 0 && electrons.value().saturated_share <= 1,
             "saturated share");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 256 * 1024) return 0;
  fuzz::Bytes in(data, size);
  if (in.u8() % 2 == 0)
    fuzz_file(in);
  else
    fuzz_camera_frame(in);
  return 0;
}
