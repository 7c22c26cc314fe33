#include "imaging/capture_model.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include <numeric>

#include "imaging/capture_descriptor.hpp"
#include "imaging/exposure_timeline.hpp"
#include "imaging/motion_frame.hpp"

namespace flutterscan::imaging {
namespace {

CaptureModel seed_capture(double blur) {
  CaptureModel m;
  m.code = LedCode::parse("2212441414112412441224111241244244242212442211444144", 3).value();
  m.blur_px = blur;
  m.led_electrons = budgeted_led_electrons(m.code, 3000, 3);
  return m;
}

double sum(const std::vector<double>& v) {
  return std::accumulate(v.begin(), v.end(), 0.0);
}

TEST(CaptureModel, BudgetCapsShortLeds) {
  const auto code =
      LedCode::parse("1111111111111111122222222222222222244444444444444444", 3).value();
  const auto I = budgeted_led_electrons(code, 3000, 3);
  EXPECT_NEAR(I[0], 3.0 * 3000.0 / 52, 1e-9);  // 17 slots: E / 17 would pass the cap c E / L
  EXPECT_NEAR(I[1], 3000.0 / 18, 1e-9);        // 18 slots: the whole budget fits under it
  const auto capped = budgeted_led_electrons(code, 3000, 1);
  EXPECT_NEAR(capped[0], 3000.0 / 52, 1e-9);  // c = 1: peak limit E / L
}

TEST(CaptureModel, PsfCarriesTheWhiteLevelOfItsChannel) {
  const CaptureModel m = seed_capture(52);
  for (int c = 0; c < 3; ++c) {
    const auto psf = channel_psf(m, c);
    EXPECT_NEAR(sum(psf), m.code.on_slots(c) * m.led_electrons[static_cast<std::size_t>(c)], 1e-9);
    EXPECT_LE(psf.size(), 54u);
  }
  // One slot per pixel through the box aperture: slot t gives half its light to
  // tap t and half to tap t + 1.
  const auto red = channel_psf(m, 0);
  const auto lit = [&](int t) { return t >= 0 && t < 52 && m.code.is_on(t, 0) ? 1.0 : 0.0; };
  for (int t = 0; t < static_cast<int>(red.size()); ++t)
    EXPECT_NEAR(red[static_cast<std::size_t>(t)], 0.5 * (lit(t) + lit(t - 1)) * m.led_electrons[0],
                1e-9)
        << t;
  // The tap-grid model: tap t is lit exactly when the code lights that LED in slot t.
  CaptureModel grid = m;
  grid.pixel_model = PixelModel::kTapGrid;
  const auto red_grid = channel_psf(grid, 0);
  EXPECT_LE(red_grid.size(), 53u);
  for (int t = 0; t < static_cast<int>(red_grid.size()); ++t)
    EXPECT_NEAR(red_grid[static_cast<std::size_t>(t)],
                m.code.is_on(t, 0) ? m.led_electrons[0] : 0.0, 1e-9)
        << t;
}

TEST(CaptureModel, SubPixelSlotsAreExact) {
  CaptureModel m = seed_capture(13);  // four slots per pixel
  m.pixel_model = PixelModel::kTapGrid;
  const auto blue = channel_psf(m, 2);
  EXPECT_EQ(blue.size(), 13u);
  for (int p = 0; p < 13; ++p) {
    int lit = 0;
    for (int t = 4 * p; t < 4 * p + 4; ++t) lit += m.code.is_on(t, 2);
    EXPECT_NEAR(blue[static_cast<std::size_t>(p)], lit * m.led_electrons[2], 1e-9);
  }
  // Through the box aperture each quarter-pixel slot spreads over two taps as
  // the mean of the triangle over it (motion_psf_test checks that integral).
  m.pixel_model = PixelModel::kBoxAperture;
  const auto aperture = channel_psf(m, 2);
  EXPECT_EQ(aperture.size(), 14u);
  for (int p = 0; p < 14; ++p) {
    double expected = 0;
    for (int t = 0; t < 52; ++t) {
      if (!m.code.is_on(t, 2)) continue;
      // The slot [t / 4, (t + 1) / 4] lies within one pixel, where tri(p - d) is
      // linear in d: its mean over the slot is its value at the slot's middle.
      const double middle = (t + 0.5) * 0.25;
      expected += std::max(0.0, 1 - std::abs(p - middle));
    }
    EXPECT_NEAR(aperture[static_cast<std::size_t>(p)], expected * m.led_electrons[2], 1e-9) << p;
  }
  const CaptureModel still = seed_capture(0);
  EXPECT_EQ(channel_psf(still, 1).size(), 1u);
}

TEST(CaptureModel, CrosstalkAndAmbientEnterEveryChannel) {
  CaptureModel m = seed_capture(52);
  m.crosstalk = {0.90, 0.08, 0.01, 0.10, 0.85, 0.12, 0.01, 0.07, 0.88};
  m.ambient_electrons = {100, 0, 0};
  double expected = 100;
  for (int k = 0; k < 3; ++k)
    expected += m.crosstalk[static_cast<std::size_t>(k)] *
                m.led_electrons[static_cast<std::size_t>(k)] * m.code.on_slots(k);
  EXPECT_NEAR(channel_white_electrons(m, 0), expected, 1e-6);
}

TEST(CaptureModel, AllChannelsAtOnceEqualEachChannelAlone) {
  // timeline_channel_psfs (the motion refinement's builder) against channel_psf,
  // with crosstalk, ambient light, both pixel models, sub-pixel and accelerating motion.
  CaptureModel m = seed_capture(52);
  m.crosstalk = {0.90, 0.08, 0.01, 0.10, 0.85, 0.12, 0.01, 0.07, 0.88};
  m.ambient_electrons = {100, 0, 40};
  for (const PixelModel pixels : {PixelModel::kBoxAperture, PixelModel::kTapGrid})
    for (const double blur : {52.0, 23.7, 61.3})
      for (const double ratio : {1.0, 1.4}) {
        m.pixel_model = pixels;
        m.blur_px = blur;
        m.speed_ratio = ratio;
        const auto all = timeline_channel_psfs(m, slot_segments(m));
        ASSERT_EQ(all.size(), 3u);
        for (int c = 0; c < 3; ++c) {
          const auto one = channel_psf(m, c);
          const auto& taps = all[static_cast<std::size_t>(c)];
          ASSERT_EQ(taps.size(), one.size()) << blur << " " << ratio << " channel " << c;
          for (std::size_t i = 0; i < one.size(); ++i)
            EXPECT_NEAR(taps[i], one[i], 1e-12 * sum(one)) << blur << " tap " << i;
        }
      }
}

TEST(CaptureModel, ProblemsAreNamed) {
  CaptureModel m = seed_capture(52);
  EXPECT_EQ(capture_model_problem(m), "");
  m.blur_px = -1;
  EXPECT_NE(capture_model_problem(m).find("blur"), std::string::npos);
  m = seed_capture(52);
  m.gain = 0;
  EXPECT_NE(capture_model_problem(m).find("gain"), std::string::npos);
  m = seed_capture(52);
  m.crosstalk.pop_back();
  EXPECT_NE(capture_model_problem(m).find("crosstalk"), std::string::npos);
}

TEST(CaptureDescriptor, RoundTrips) {
  CaptureModel m = seed_capture(37.5);
  m.direction = Direction::kMinusY;
  m.crosstalk = {0.90, 0.08, 0.01, 0.10, 0.85, 0.12, 0.01, 0.07, 0.88};
  m.encoding = Encoding::kSrgb;
  m.black_level = 64;
  m.block_offsets_px = {0.25, -0.5, 0.125};
  const auto back = from_descriptor(to_descriptor(m));
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_EQ(back.value().code, m.code);
  EXPECT_EQ(back.value().direction, Direction::kMinusY);
  EXPECT_EQ(back.value().crosstalk, m.crosstalk);
  EXPECT_EQ(back.value().blur_px, 37.5);
  EXPECT_EQ(back.value().encoding, Encoding::kSrgb);
  EXPECT_EQ(back.value().black_level, 64);
  EXPECT_EQ(back.value().block_offsets_px, m.block_offsets_px);
  EXPECT_EQ(to_descriptor(back.value()), to_descriptor(m));
  EXPECT_FALSE(to_descriptor(seed_capture(52)).contains("block_offsets_px"));  // none: not written
  for (PixelModel pixel :
       {PixelModel::kBoxAperture, PixelModel::kBandLimited, PixelModel::kTapGrid}) {
    CaptureModel p = seed_capture(52);
    p.pixel_model = pixel;
    const auto read = from_descriptor(to_descriptor(p));
    ASSERT_TRUE(read.ok()) << read.error();
    EXPECT_EQ(read.value().pixel_model, pixel);
  }
}

TEST(CaptureDescriptor, BadFieldsAreNamed) {
  auto d = to_descriptor(seed_capture(52));
  d["blur_px"] = "fast";
  EXPECT_EQ(from_descriptor(d).error(), "field 'blur_px' must be a number");
  d = to_descriptor(seed_capture(52));
  d.erase("gain_e_per_dn");
  EXPECT_EQ(from_descriptor(d).error(), "missing field 'gain_e_per_dn'");
  d = to_descriptor(seed_capture(52));
  d["version"] = 9;
  EXPECT_NE(from_descriptor(d).error().find("version 9"), std::string::npos);
  d = to_descriptor(seed_capture(52));
  d["code"] = "12x4";
  EXPECT_NE(from_descriptor(d).error().find("slot 2"), std::string::npos);
  d = to_descriptor(seed_capture(52));
  d["crosstalk"][1] = {1, 2};
  EXPECT_NE(from_descriptor(d).error().find("row 1"), std::string::npos);
  d = to_descriptor(seed_capture(52));
  d["block_offsets_px"] = {0.5, "x"};
  EXPECT_NE(from_descriptor(d).error().find("block_offsets_px"), std::string::npos);
  d["block_offsets_px"] = {0.5, 1e9};
  EXPECT_NE(from_descriptor(d).error().find("backwards"), std::string::npos);
  d = to_descriptor(seed_capture(52));
  d["pixel_model"] = "gaussian";
  EXPECT_NE(from_descriptor(d).error().find("band-limited"), std::string::npos);
  d = to_descriptor(seed_capture(52));
  d["led_electrons_per_slot"] = {400.0};
  EXPECT_EQ(from_descriptor(d).error(),
            "field 'led_electrons_per_slot' needs one entry per LED (3)");
  d = to_descriptor(seed_capture(52));
  d["ambient_electrons"] = {0.0};
  EXPECT_EQ(from_descriptor(d).error(),
            "field 'ambient_electrons' needs one entry per channel (3)");
  d = to_descriptor(seed_capture(52));
  d["bit_depth"] = 17;
  EXPECT_EQ(from_descriptor(d).error(), "field 'bit_depth' must be 1 to 16");
  EXPECT_FALSE(from_descriptor(nlohmann::json::array()).ok());
}

// What the files camera takes of a descriptor: every field optional, checked as
// from_descriptor checks the ones they share, the capture object's by its path.
TEST(CaptureDescriptor, RecordedFrameFieldsAreOptionalAndChecked) {
  auto d = to_descriptor(seed_capture(52));
  d["capture"] = {{"sequence", 9}, {"timestamp_ns", -5}, {"truth", {"A", "B"}}};
  const auto read = recorded_frame_from_descriptor(d);
  ASSERT_TRUE(read.ok()) << read.error();
  EXPECT_EQ(read.value().bit_depth, 12);
  EXPECT_FALSE(read.value().bayer_rggb);
  EXPECT_EQ(read.value().sequence, 9u);
  EXPECT_EQ(read.value().timestamp_ns, -5);
  EXPECT_EQ(read.value().truth, (std::vector<std::string>{"A", "B"}));
  EXPECT_TRUE(read.value().truth_in_view.empty());
  const auto bare = recorded_frame_from_descriptor(nlohmann::json::object());
  ASSERT_TRUE(bare.ok()) << bare.error();
  EXPECT_FALSE(bare.value().bit_depth || bare.value().sequence || bare.value().timestamp_ns);
  const std::pair<const char*, std::string> refused[] = {
      {R"({"bit_depth": 0})", "field 'bit_depth' must be 1 to 16"},
      {R"({"bayer": "BGGR"})", "field 'bayer' must be \"RGGB\" or null"},
      {R"({"capture": []})", "field 'capture' must be an object"},
      {R"({"capture": {"sequence": -1}})", "field 'capture.sequence' must be a whole number >= 0"},
      {R"({"capture": {"timestamp_ns": 1.5}})",
       "field 'capture.timestamp_ns' must be a whole number of nanoseconds (64-bit signed)"},
      {R"({"capture": {"truth_in_view": ["A", 1]}})",
       "field 'capture.truth_in_view' must hold only strings"}};
  for (const auto& [text, message] : refused) {
    const auto r = recorded_frame_from_descriptor(nlohmann::json::parse(text));
    ASSERT_FALSE(r.ok()) << text;
    EXPECT_EQ(r.error(), message) << text;
  }
}

TEST(MotionFrame, EveryDirectionRoundTrips) {
  Plane p(5, 3);
  for (std::size_t i = 0; i < p.pixels.size(); ++i) p.pixels[i] = static_cast<float>(i);
  for (Direction d :
       {Direction::kPlusX, Direction::kMinusX, Direction::kPlusY, Direction::kMinusY}) {
    const Plane moved = to_motion_frame(p, d);
    EXPECT_EQ(from_motion_frame(moved, d).pixels, p.pixels);
  }
  // +y: the motion runs down the columns, so column 0 becomes row 0.
  const Plane down = to_motion_frame(p, Direction::kPlusY);
  EXPECT_EQ(down.width, 3);
  EXPECT_EQ(down.at(1, 0), p.at(0, 1));
  EXPECT_EQ(to_motion_frame(p, Direction::kMinusX).at(0, 0), p.at(4, 0));
}

TEST(MotionFrame, TurnsAFrameOnceAndBack) {
  Image camera;
  for (int c = 0; c < 2; ++c) {
    Plane p(5, 3);
    for (std::size_t i = 0; i < p.pixels.size(); ++i) p.pixels[i] = static_cast<float>(10 * c + i);
    camera.channels.push_back(p);
  }
  for (Direction d :
       {Direction::kPlusX, Direction::kMinusX, Direction::kPlusY, Direction::kMinusY}) {
    const auto frame = MotionFrame::make(camera, d);
    ASSERT_TRUE(frame.ok()) << frame.error();
    EXPECT_EQ(frame.value().direction(), d);
    EXPECT_EQ(frame.value().channel_count(), 2);
    EXPECT_EQ(frame.value().along(), length_along_motion(d, 5, 3));
    EXPECT_EQ(frame.value().lines(), moves_along_x(d) ? 3 : 5);
    for (int c = 0; c < 2; ++c) {
      const Plane& plane = camera.channels[static_cast<std::size_t>(c)];
      EXPECT_EQ(frame.value().channel(c).pixels, to_motion_frame(plane, d).pixels);
      EXPECT_EQ(frame.value().to_camera(frame.value().channel(c)).pixels, plane.pixels);
    }
    // Camera pixel (x, y) lies at column position_along_motion of the motion frame.
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 5; ++x) {
        const auto n = static_cast<int>(position_along_motion(d, x, y, 5, 3));
        const int row = moves_along_x(d) ? y : x;
        EXPECT_EQ(frame.value().channel(0).at(n, row), camera.channels[0].at(x, y))
            << static_cast<int>(d) << " " << x << "," << y;
      }
  }
  // The one check at the entry: what no stage could work on is refused by name.
  Image uneven = camera;
  uneven.channels[1] = Plane(4, 3);
  const auto refused = MotionFrame::make(uneven, Direction::kPlusY);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().find("channel 1"), std::string::npos) << refused.error();
  Image wild = camera;
  wild.channels[0].pixels[7] = NAN;
  EXPECT_FALSE(MotionFrame::make(wild, Direction::kPlusX).ok());
  EXPECT_FALSE(MotionFrame::make(Image{}, Direction::kPlusX).ok());
}

}  // namespace
}  // namespace flutterscan::imaging
