// Scheme auto's light probe: the probe lights every LED in every slot; the sim
// line's light is measured from its brightest paper (reflectance 0.9, taken as
// white: 0.9 of the truth); the regime map's choice follows the measured light,
// and a configured light is the fallback when the frames cannot give one.
#include "session/light_probe.hpp"

#include <gtest/gtest.h>

#include <string>

#include "session/test/session_test_support.hpp"

namespace flutterscan::session {
namespace {

using testing::small_sim_config;

/// A sim line whose camera's true light is `electrons` per channel (read noise 4 e-), code "auto".
SessionConfig probe_config(double electrons) {
  SessionConfig config = small_sim_config("unused", 8);
  config.camera.options.emplace_back("electrons", std::to_string(electrons));
  config.controller.code = "auto";
  config.optics.read_noise_e = 4;
  EXPECT_EQ(check_config(config), "");
  return config;
}

void ignore(const std::string&) {}

TEST(LightProbe, ThePatternLightsEveryLedInEverySlot) {
  const LedCode probe = light_probe_pattern();
  EXPECT_EQ(probe.length(), 52);
  for (int t = 0; t < probe.length(); ++t) EXPECT_EQ(probe.mask(t), 7) << t;
  EXPECT_EQ(light_probe_pattern(17).length(), 17);
}

TEST(LightProbe, MeasuresTheSimLinesLightFromItsBrightestPaper) {
  const SessionConfig config = probe_config(3000);
  const auto level = measure_light_level(config, nullptr, ignore);
  ASSERT_TRUE(level.ok()) << level.error().message;
  EXPECT_EQ(level.value().frames, config.controller.probe_frames);
  EXPECT_GT(level.value().pixels, 1000);
  EXPECT_NEAR(level.value().electrons / 3000, 0.9, 0.03);  // paper 0.9 taken as white
}

TEST(LightProbe, TheSchemeFollowsTheMeasuredLight) {
  // The map at read noise 4 e-, cap 3: a 2-slot white strobe at 1000 e-.
  SessionConfig config = probe_config(1000);
  const auto light = choose_scheme_from_light(config, nullptr, ignore);
  ASSERT_TRUE(light.ok()) << light.error().message;
  ASSERT_TRUE(light.value().level);
  ASSERT_TRUE(config.controller.scheme);
  EXPECT_EQ(config.controller.scheme->scheme, "snapshot-2");
  EXPECT_EQ(config.optics.electrons, light.value().electrons);  // the frames' model uses it
  EXPECT_NEAR(light.value().electrons / 1000, 0.9, 0.03);
  EXPECT_EQ(scheme_light_json(light.value())["source"], "measured");
  EXPECT_EQ(describe_scheme_light(light.value()).rfind("light measured ", 0), 0u);
}

TEST(LightProbe, SaturatedPaperFailsUnlessTheConfigGivesTheLight) {
  SessionConfig config = probe_config(20000);
  const auto failed = choose_scheme_from_light(config, nullptr, ignore);
  ASSERT_FALSE(failed.ok());
  EXPECT_NE(failed.error().message.find("could not be measured"), std::string::npos)
      << failed.error().message;
  EXPECT_FALSE(failed.error().bad_input);

  config.optics.electrons = 3000;
  config.optics.electrons_given = true;
  const auto fallback = choose_scheme_from_light(config, nullptr, ignore);
  ASSERT_TRUE(fallback.ok()) << fallback.error().message;
  EXPECT_FALSE(fallback.value().level);
  EXPECT_EQ(fallback.value().electrons, 3000);
  EXPECT_NE(fallback.value().not_measured.find("saturates"), std::string::npos)
      << fallback.value().not_measured;
  EXPECT_EQ(config.controller.scheme->scheme, "found-mse");  // the 3000 e-, 4 e- cell
  EXPECT_EQ(config.optics.electrons, 3000);
  EXPECT_EQ(scheme_light_json(fallback.value())["source"], "configured");
}

}  // namespace
}  // namespace flutterscan::session
