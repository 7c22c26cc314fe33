// Model choice inside a whole sim session: a line without an encoder gets each
// frame's blur from the frame (the configured nominal blur is 8% off), every
// frame's log says which model it used and which guards fired, and the summary
// counts both.
#include <gtest/gtest.h>

#include <fstream>

#include "imaging/flat_field.hpp"
#include "session/session.hpp"
#include "session/test/session_test_support.hpp"

namespace flutterscan::session {
namespace {

namespace fs = std::filesystem;
using namespace testing;

TEST(SimSessionModels, WithoutAnEncoderEachFrameEstimatesItsBlur) {
  const fs::path out = fresh_folder("no_encoder");
  SessionConfig config = small_sim_config(out, 40);
  config.optics.encoder = false;
  config.optics.nominal_blur_px = 48;  // the belt runs 52 px per exposure
  std::atomic<bool> stop{false};
  const SessionOutcome outcome = run_session(config, stop, {});
  ASSERT_EQ(outcome.error, "");
  const auto& s = outcome.summary;
  EXPECT_EQ(s["ground_truth"]["missed"], nlohmann::json::array()) << s.dump(2);
  EXPECT_EQ(s["models_chosen"]["grey latent, global code phase, blur estimated from the frame"],
            s["frames_processed"])
      << s.dump(2);
  int bad = 0, estimated = 0;
  for (const auto& line : read_jsonl(out / "session.jsonl", bad)) {
    if (!line.contains("times_ms")) continue;  // dropped (processing behind): never deblurred
    ASSERT_TRUE(line.contains("model")) << line.dump();
    ASSERT_TRUE(line.contains("guards")) << line.dump();
    if (line.contains("blur_estimate_se_px")) {
      ++estimated;
      EXPECT_NEAR(line["model"]["blur_px"].get<double>(), 52.0, 0.5) << line.dump();
    }
  }
  EXPECT_EQ(bad, 0);
  EXPECT_GT(estimated, 10);  // frames with a label in view; the rest keep the nominal blur
}

TEST(SimSessionModels, SchemeAutoFollowsTheRegimeMap) {
  const fs::path out = fresh_folder("scheme_auto");
  SessionConfig config = small_sim_config(out, 30);
  config.controller.code = "auto";
  config.optics.electrons = 3000;
  config.optics.read_noise_e = 1;  // a quiet sensor: a 1-slot white strobe wins there
  std::atomic<bool> stop{false};
  std::vector<std::string> messages;
  SessionHooks hooks;
  hooks.message = [&](const std::string& m) { messages.push_back(m); };
  const SessionOutcome outcome = run_session(config, stop, hooks);
  ASSERT_EQ(outcome.error, "");
  const auto& s = outcome.summary;
  EXPECT_EQ(s["scheme_choice"]["scheme"], "snapshot-1") << s.dump(2);
  EXPECT_LT(s["scheme_choice"]["expected_margin_db"].get<double>(), 0);
  EXPECT_EQ(s["frames_processed"], 30);
  EXPECT_EQ(s["ground_truth"]["missed"], nlohmann::json::array()) << s.dump(2);
  ASSERT_FALSE(messages.empty());
  EXPECT_NE(messages.front().find("scheme auto: snapshot-1"), std::string::npos)
      << messages.front();
  // A noisy sensor at the same light: the optimised triplet.
  SessionConfig noisy = config;
  noisy.optics.read_noise_e = 30;
  ASSERT_EQ(check_config(noisy), "");
  EXPECT_EQ(noisy.controller.scheme->scheme, "found-mse");
}

TEST(SimSessionModels, AFlatFieldIsAppliedAndABadOneRefusedBeforeStart) {
  const fs::path out = fresh_folder("flat_field");
  // A flat field of uniform light (every tile the same mixing): labels still read.
  imaging::FlatField flat;
  flat.width = 640;
  flat.height = 240;
  flat.tiles_x = 4;
  flat.tiles_y = 2;
  flat.channels = flat.leds = 3;
  flat.reference = {900, 80, 10, 100, 850, 120, 10, 70, 880};
  for (int t = 0; t < 8; ++t)
    flat.mixing.insert(flat.mixing.end(), flat.reference.begin(), flat.reference.end());
  const fs::path file = out / "flat.json";
  std::ofstream(file) << imaging::flat_field_to_json(flat).dump();
  SessionConfig config = small_sim_config(out, 30);
  config.optics.flat_field = file.string();
  std::atomic<bool> stop{false};
  const SessionOutcome outcome = run_session(config, stop, {});
  ASSERT_EQ(outcome.error, "");
  EXPECT_EQ(outcome.summary["ground_truth"]["missed"], nlohmann::json::array());
  EXPECT_EQ(outcome.summary["frames_failed"], 0);
  // A broken file: refused as bad input, before any controller or camera is touched.
  std::ofstream(file) << "{\"format\": \"flutterscan-flat-field\"}";
  const SessionOutcome refused = run_session(config, stop, {});
  EXPECT_TRUE(refused.bad_input);
  EXPECT_NE(refused.error.find("optics.flat_field"), std::string::npos) << refused.error;
  EXPECT_TRUE(refused.folder.empty());
}

}  // namespace
}  // namespace flutterscan::session
