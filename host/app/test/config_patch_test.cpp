// Calibration results go into a user's session config without disturbing it:
// only the named keys of [optics] change, comments and other tables stay, and
// the result is a config the session reads back with the new values.

#include <gtest/gtest.h>

#include "app/config_patch.hpp"
#include "session/session_config.hpp"

namespace flutterscan::app {
namespace {

const char* kConfig = R"(# line 3, hall B
[camera]
spec = "sim"  # the virtual conveyor

[optics]
# measured 2025-03-01
crosstalk = [1.0, 0.0, 0.0,
             0.0, 1.0, 0.0,
             0.0, 0.0, 1.0]
px_per_count = 0.5 # from the drawing

[output]
dir = "out"
)";

TEST(ConfigPatch, ReplacesKeysKeepsEverythingElse) {
  const std::string patched = patch_toml_table(
      kConfig, "optics",
      {{"crosstalk", toml_number_matrix({0.9, 0.08, 0.01, 0.1, 0.85, 0.12, 0.01, 0.07, 0.88}, 3)},
       {"px_per_count", toml_number(0.25)},
       {"read_noise_e", toml_number(3.5)}},
      "calibrated");
  EXPECT_NE(patched.find("# line 3, hall B"), std::string::npos);
  EXPECT_NE(patched.find("# measured 2025-03-01"), std::string::npos);
  EXPECT_NE(patched.find("spec = \"sim\"  # the virtual conveyor"), std::string::npos);
  EXPECT_EQ(patched.find("0.0, 1.0, 0.0,"), std::string::npos);  // the old array is gone
  EXPECT_EQ(patched.find("from the drawing"), std::string::npos);
  EXPECT_LT(patched.find("read_noise_e = 3.5"), patched.find("[output]"));  // appended in [optics]
  const auto config = session::parse_config(patched, "patched");
  ASSERT_TRUE(config.ok()) << config.error() << "\n" << patched;
  EXPECT_DOUBLE_EQ(config.value().optics.px_per_count, 0.25);
  EXPECT_DOUBLE_EQ(config.value().optics.read_noise_e, 3.5);
  EXPECT_DOUBLE_EQ(config.value().optics.crosstalk[5], 0.12);
  EXPECT_EQ(config.value().output.dir, "out");
}

TEST(ConfigPatch, AddsTheTableWhenMissing) {
  const std::string patched =
      patch_toml_table("[camera]\nspec = \"sim\"\n", "optics", {{"gain_e_per_dn", "2.5"}}, "");
  EXPECT_EQ(patched, "[camera]\nspec = \"sim\"\n\n[optics]\ngain_e_per_dn = 2.5\n");
  const auto config = session::parse_config(patched, "patched");
  ASSERT_TRUE(config.ok()) << config.error();
  EXPECT_DOUBLE_EQ(config.value().optics.gain_e_per_dn, 2.5);
  EXPECT_EQ(patch_toml_table("", "optics", {{"cap", "3.0"}}, ""), "[optics]\ncap = 3.0\n");
}

TEST(ConfigPatch, NumbersStayFloats) {
  EXPECT_EQ(toml_number(2), "2.0");
  EXPECT_EQ(toml_number(0.123456789), "0.123457");
  EXPECT_EQ(toml_number_array({1, 0.5}), "[1.0, 0.5]");
  EXPECT_EQ(toml_number_matrix({1, 0, 0, 1}, 2), "[[1.0, 0.0], [0.0, 1.0]]");
}

}  // namespace
}  // namespace flutterscan::app
