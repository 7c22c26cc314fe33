// frame_to_electrons: the one-pass conversion the session's workers use gives
// what the three-step path gives (frame_to_dn, saturated_share, dn_to_electrons).

#include "capture/frame_pixels.hpp"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "imaging/frame_conversion.hpp"
#include "imaging/model_guards.hpp"
#include "imaging/motion_frame.hpp"

namespace flutterscan::capture {
namespace {

/// A frame of random samples (some at the ceiling), rows padded to `stride_extra` bytes more.
Frame random_frame(PixelFormat format, int bit_depth, int stride_extra) {
  Frame frame;
  frame.sequence = 9;
  const int width = 37, height = 11;
  const int bpp = bytes_per_pixel(format);
  frame.format = {width, height, format, bit_depth,
                  static_cast<std::size_t>(width * bpp + stride_extra)};
  frame.data.resize(frame.format.row_bytes * height);
  std::mt19937 random(static_cast<unsigned>(bpp * 100 + bit_depth));
  const int top = (1 << bit_depth) - 1;
  std::uniform_int_distribution<int> sample(0, top + top / 4);  // a fifth or so saturated
  const bool wide = bpp == 2 || bpp == 6;
  for (std::size_t i = 0; i + (wide ? 1 : 0) < frame.data.size(); i += wide ? 2 : 1) {
    const int v = std::min(sample(random), top);
    frame.data[i] = static_cast<std::uint8_t>(v & 0xff);
    if (wide) frame.data[i + 1] = static_cast<std::uint8_t>(v >> 8);
  }
  return frame;
}

imaging::CaptureModel camera(int bit_depth, int channels) {
  imaging::CaptureModel m;
  m.channels = channels;
  m.bit_depth = bit_depth;
  m.black_level = bit_depth > 8 ? 64 : 16;
  m.full_well = 9000;  // below the code ceiling for 12 bits: the well saturates first
  m.gain = bit_depth > 8 ? 12000.0 / 4095.0 : 40;
  return m;
}

TEST(FrameToElectrons, OnePassEqualsTheThreeStepsForEveryFastFormat) {
  const struct {
    PixelFormat format;
    int bit_depth;
    int channels;
  } cases[] = {{PixelFormat::kRgb8, 8, 3},        {PixelFormat::kBgr8, 8, 3},
               {PixelFormat::kRgb16, 12, 3},      {PixelFormat::kMono8, 8, 1},
               {PixelFormat::kMono16, 12, 1},     {PixelFormat::kBayerRggb8, 8, 1},
               {PixelFormat::kBayerRggb16, 12, 1}};
  for (const auto& c : cases) {
    SCOPED_TRACE(pixel_format_name(c.format));
    const Frame frame = random_frame(c.format, c.bit_depth, 5);
    const imaging::CaptureModel m = camera(c.bit_depth, c.channels);
    const auto dn = frame_to_dn(frame);
    ASSERT_TRUE(dn.ok()) << dn.error();
    const imaging::Image expected = imaging::dn_to_electrons(dn.value(), m);
    const auto fast = frame_to_electrons(frame, m);
    ASSERT_TRUE(fast.ok()) << fast.error();
    const double share = imaging::saturated_share(dn.value(), m);
    EXPECT_GT(share, 0.05);  // the frames do have saturated samples
    EXPECT_DOUBLE_EQ(fast.value().saturated_share, share);
    ASSERT_EQ(fast.value().electrons.channel_count(), expected.channel_count());
    // The row levels made while converting are the converted rows' (bit for bit);
    // a Bayer mosaic's rows are no motion frame's.
    const bool mosaic = is_bayer_mosaic(c.format);
    EXPECT_EQ(fast.value().levels.empty(), mosaic);
    const imaging::RowLevels levels = imaging::RowLevels::of(fast.value().electrons);
    for (int ch = 0; ch < (mosaic ? 0 : expected.channel_count()); ++ch)
      for (int y = 0; y < expected.height(); ++y) {
        ASSERT_EQ(fast.value().levels.at(ch, y).sum, levels.at(ch, y).sum) << ch << ", " << y;
        ASSERT_EQ(fast.value().levels.at(ch, y).worst_mean_square,
                  levels.at(ch, y).worst_mean_square);
      }
    for (int ch = 0; ch < expected.channel_count(); ++ch)
      for (std::size_t i = 0; i < expected.channels[ch].pixels.size(); ++i)
        ASSERT_NEAR(fast.value().electrons.channels[ch].pixels[i], expected.channels[ch].pixels[i],
                    1e-3)
            << "channel " << ch << ", sample " << i;
  }
}

TEST(FrameToElectrons, NonLinearEncodingsTakeTheThreeStepPath) {
  const Frame frame = random_frame(PixelFormat::kRgb8, 8, 0);
  imaging::CaptureModel m = camera(8, 3);
  m.encoding = imaging::Encoding::kSrgb;
  const auto dn = frame_to_dn(frame);
  const auto fast = frame_to_electrons(frame, m);
  ASSERT_TRUE(dn.ok() && fast.ok());
  const imaging::Image expected = imaging::dn_to_electrons(dn.value(), m);
  EXPECT_EQ(fast.value().electrons.channels[1].pixels, expected.channels[1].pixels);
  EXPECT_TRUE(fast.value().levels.empty());  // MotionFrame::make makes them
}

// The one-pass conversion says when its inputs bound every value within kMaxPixelValue, so that
// MotionFrame::make need not read them again; where they do not (a wild black level or gain),
// the values are read, and an out-of-range one is still refused naming where it is.
TEST(FrameToElectrons, SaysWhenTheBlackLevelAndGainBoundTheValues) {
  const Frame frame = random_frame(PixelFormat::kRgb16, 12, 0);
  const auto usual = frame_to_electrons(frame, camera(12, 3));
  ASSERT_TRUE(usual.ok()) << usual.error();
  EXPECT_EQ(usual.value().values, imaging::PixelValues::kShownInRange);

  imaging::CaptureModel wild = camera(12, 3);
  wild.black_level = 1e85;  // inf as a float: (sample - black) x gain is -inf
  auto unbounded = frame_to_electrons(frame, wild);
  ASSERT_TRUE(unbounded.ok()) << unbounded.error();
  EXPECT_EQ(unbounded.value().values, imaging::PixelValues::kScan);
  const auto refused = imaging::MotionFrame::make(
      std::move(unbounded.value().electrons), imaging::Direction::kPlusX, unbounded.value().values);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().find("not a finite number"), std::string::npos) << refused.error();

  // 65535 x 1e10 e-/DN is within 1e15, but not with the factor of 2 the bound keeps for rounding.
  imaging::CaptureModel steep = camera(12, 3);
  steep.gain = 1e10;
  steep.black_level = 0;
  const auto near_limit = frame_to_electrons(frame, steep);
  ASSERT_TRUE(near_limit.ok()) << near_limit.error();
  EXPECT_EQ(near_limit.value().values, imaging::PixelValues::kScan);
}

TEST(FrameToElectrons, ShortDataIsRefusedNamingTheFrame) {
  Frame frame = random_frame(PixelFormat::kRgb16, 12, 0);
  frame.data.resize(frame.data.size() - 1);
  const auto fast = frame_to_electrons(frame, camera(12, 3));
  ASSERT_FALSE(fast.ok());
  EXPECT_NE(fast.error().find("frame 9"), std::string::npos) << fast.error();
  EXPECT_NE(fast.error().find("needs more"), std::string::npos) << fast.error();
}

/// An MJPEG frame of `width` x `height` px declared by the format (the data as given).
Frame mjpeg_frame(std::vector<std::uint8_t> data, int width, int height) {
  Frame frame;
  frame.sequence = 4;
  frame.format = {width, height, PixelFormat::kMjpeg, 8, 0};
  frame.data = std::move(data);
  return frame;
}

TEST(FrameToDn, MjpegDecodesWhenItsHeaderDeclaresTheFormatsSize) {
  cv::Mat bgr(24, 48, CV_8UC3, cv::Scalar(30, 120, 210));
  std::vector<std::uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", bgr, jpeg));
  const auto decoded = frame_to_dn(mjpeg_frame(jpeg, 48, 24));
  ASSERT_TRUE(decoded.ok()) << decoded.error();
  EXPECT_EQ(decoded.value().channels.size(), 3u);
  EXPECT_NEAR(decoded.value().channels[0].at(10, 10), 210, 4);  // red
  EXPECT_NEAR(decoded.value().channels[2].at(10, 10), 30, 4);   // blue

  // Another size than the format's is refused from the header, naming both.
  const auto other = frame_to_dn(mjpeg_frame(jpeg, 40, 24));
  ASSERT_FALSE(other.ok());
  EXPECT_NE(other.error().find("frame 4: MJPEG data declares 48x24 px, the frame format 40x24"),
            std::string::npos)
      << other.error();
}

TEST(FrameToDn, MjpegDeclaringAHugeFrameIsRefusedBeforeDecoding) {
  // A header declaring 30000 x 30000 px (2.7 GB decoded) and no image data: refused
  // from the header, before the decoder sizes its output by it.
  const std::vector<std::uint8_t> bomb = {
      0xFF, 0xD8,                                                  // start of image
      0xFF, 0xC0, 0x00, 0x11, 0x08, 0x75, 0x30, 0x75, 0x30,        // SOF0: 8 bit, 30000 x 30000
      0x03, 0x01, 0x22, 0x00, 0x02, 0x11, 0x01, 0x03, 0x11, 0x01,  // three components
      0xFF, 0xD9};                                                 // end of image
  const auto result = frame_to_dn(mjpeg_frame(bomb, 48, 24));
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.error().find("declares 30000x30000 px"), std::string::npos) << result.error();
  // Nor does a format that large get as far as the header.
  const auto huge = frame_to_dn(mjpeg_frame(bomb, 30000, 30000));
  ASSERT_FALSE(huge.ok());
  EXPECT_NE(huge.error().find("30000x30000 px is beyond the largest frame"), std::string::npos)
      << huge.error();

  // Not JPEG (a PNG's signature) and a header segment running past the data: refused.
  const auto png = frame_to_dn(mjpeg_frame({0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A}, 48, 24));
  ASSERT_FALSE(png.ok());
  EXPECT_NE(png.error().find("not JPEG data"), std::string::npos) << png.error();
  const auto cut = frame_to_dn(mjpeg_frame({0xFF, 0xD8, 0xFF, 0xC0, 0x00, 0x11, 0x08}, 48, 24));
  ASSERT_FALSE(cut.ok());
  EXPECT_NE(cut.error().find("runs past the data"), std::string::npos) << cut.error();
}

}  // namespace
}  // namespace flutterscan::capture
