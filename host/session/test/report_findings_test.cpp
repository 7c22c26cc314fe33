// What report.html's first screen says went wrong: each finding from the
// summary's figures, problems first, and one "nothing went wrong" otherwise.
#include "session/report_findings.hpp"

#include <gtest/gtest.h>

namespace flutterscan::session {
namespace {

nlohmann::json clean_summary() {
  return {{"frames_captured", 600u},
          {"frames_processed", 600u},
          {"frames_dropped", 0u},
          {"frames_failed", 0u},
          {"objects", 40u},
          {"objects_read", 40u},
          {"frames_flagged", nlohmann::json::object()}};
}

bool mentions(const Finding& f, const std::string& text) {
  return (f.what + " " + f.to_do).find(text) != std::string::npos;
}

TEST(ReportFindings, ACleanSessionSaysNothingWentWrong) {
  const auto findings = report_findings(clean_summary());
  ASSERT_EQ(findings.size(), 1u);
  EXPECT_EQ(findings[0].severity, Finding::Severity::kGood);
  EXPECT_TRUE(mentions(findings[0], "every object was read"));
}

TEST(ReportFindings, NoReadsDropsAndLostFramesAreNamedWithTheirFiguresProblemsFirst) {
  auto s = clean_summary();
  s["objects_read"] = 39u;    // 97.5%: a warning
  s["frames_dropped"] = 30u;  // 5% of captured: a problem
  s["camera_frames_lost"] = 2u;
  s["frames_without_event"] = 1u;
  s["frames_flagged"] = {{"saturated", 4u}, {"blur-off-encoder", 3u}, {"motion-unfit", 2u}};
  const auto findings = report_findings(s);
  ASSERT_GE(findings.size(), 5u);
  EXPECT_EQ(findings[0].severity, Finding::Severity::kProblem);
  EXPECT_TRUE(mentions(findings[0], "30 frames of 600 captured were dropped"));
  for (std::size_t i = 1; i < findings.size(); ++i)
    EXPECT_LE(findings[i - 1].severity, findings[i].severity) << i;
  auto find = [&](const std::string& text) {
    for (const auto& f : findings)
      if (mentions(f, text)) return &f;
    return static_cast<const Finding*>(nullptr);
  };
  const Finding* no_read = find("1 of 40 objects were not read");
  ASSERT_NE(no_read, nullptr);
  EXPECT_EQ(no_read->severity, Finding::Severity::kWarning);
  EXPECT_TRUE(mentions(*no_read, "97.5%"));
  EXPECT_TRUE(mentions(*no_read, "flutterscan replay"));
  EXPECT_NE(find("The camera lost 2 frames"), nullptr);
  EXPECT_NE(find("1 frame arrived without an exposure event"), nullptr);
  EXPECT_NE(find("4 frames saturated"), nullptr);
  const Finding* motion = find("5 frames did not match the motion");
  ASSERT_NE(motion, nullptr);
  EXPECT_TRUE(mentions(*motion, "calibrate speed"));
  for (const auto& f : findings)
    EXPECT_FALSE(f.to_do.empty() && f.severity != Finding::Severity::kNote) << f.what;
}

TEST(ReportFindings, AReadRateBelowNinetyFivePercentAndErrorsAreProblems) {
  auto s = clean_summary();
  s["objects_read"] = 30u;
  s["error"] = "camera 'v4l2:/dev/video0' went away";
  s["frames_failed"] = 3u;
  s["frames_flagged"] = {{"blur-out-of-range", 3u}};
  const auto findings = report_findings(s);
  ASSERT_GE(findings.size(), 3u);
  EXPECT_TRUE(mentions(findings[0], "went away"));
  int problems = 0;
  for (const auto& f : findings) problems += f.severity == Finding::Severity::kProblem;
  EXPECT_EQ(problems, 3);
  bool blur = false;
  for (const auto& f : findings) blur = blur || mentions(f, "3 with a blur out of range");
  EXPECT_TRUE(blur);
}

TEST(ReportFindings, ASessionWithoutObjectsSaysSo) {
  auto s = clean_summary();
  s["objects"] = 0u;
  s["objects_read"] = 0u;
  const auto findings = report_findings(s);
  ASSERT_EQ(findings.size(), 1u);
  EXPECT_EQ(findings[0].severity, Finding::Severity::kWarning);
  EXPECT_TRUE(mentions(findings[0], "No object passed the camera"));
}

}  // namespace
}  // namespace flutterscan::session
