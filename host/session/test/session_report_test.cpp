// report.html for people: the first screen says how the session went in words
// (verdict, figures, findings), NO-READs come before the rest, long object
// tables are folded after their first rows, and no summary key shows as is.
#include "session/session_report.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "session/test/session_test_support.hpp"

namespace flutterscan::session {
namespace {

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

ObjectResult object(std::uint64_t id, const std::string& value) {
  ObjectResult o;
  o.id = id;
  o.value = value;
  o.format = value.empty() ? "" : "Code128";
  o.frames_seen = 4;
  o.frames_decoded = value.empty() ? 0 : 3;
  return o;
}

TEST(SessionReport, TheFirstScreenSaysHowItWentInWords) {
  testing::ScratchFolder scratch("report_words");
  ReportInputs in;
  in.summary = {{"camera", "sim"},
                {"controller", "virtual controller"},
                {"code", "seed-maxmin-1"},
                {"method", "cascade"},
                {"frames_captured", 300u},
                {"frames_processed", 290u},
                {"frames_dropped", 10u},
                {"frames_failed", 0u},
                {"objects", 50u},
                {"objects_read", 48u},
                {"object_read_rate", 0.96},
                {"mean_decode_rate_per_object", 0.75},
                {"fps", 29.9},
                {"latency_ms_p50", 40.0},
                {"latency_ms_p99", 80.5},
                {"object_results_omitted", 0u},
                {"frames_flagged", nlohmann::json::object()}};
  for (std::uint64_t i = 1; i <= 50; ++i)
    in.objects.push_back(object(i, i == 7 || i == 31 ? "" : "FS-" + std::to_string(i)));
  for (double ms : {30.0, 40.0, 80.0}) in.latency_ms.add(ms);
  ASSERT_EQ(write_report(scratch.path().string(), in), "");
  const std::string html = read_text(scratch.path() / "report.html");
  // The verdict, before anything else: read rate, NO-READs and drops in a sentence.
  const auto verdict = html.find("id=\"verdict\"");
  ASSERT_NE(verdict, std::string::npos);
  EXPECT_NE(html.find("Read rate 96.0%: 48 of 50 objects read, 2 NO-READs, 10 frames dropped"),
            std::string::npos);
  EXPECT_LT(verdict, html.find("<h2>"));
  // Coloured by the worst finding: over 1% of the frames dropped is a problem.
  EXPECT_NE(html.find("class=\"verdict problem\""), std::string::npos);
  // What went wrong and what to do, on the first screen: both findings, with a step.
  const auto findings = html.find("What went wrong, and what to do");
  ASSERT_NE(findings, std::string::npos);
  EXPECT_NE(html.find("2 of 50 objects were not read", findings), std::string::npos);
  EXPECT_NE(html.find("10 frames of 300 captured were dropped", findings), std::string::npos);
  EXPECT_NE(html.find("class=\"todo\"", findings), std::string::npos);
  // NO-READs before the pictures, charts and the object table.
  const auto no_reads = html.find("<h2>NO-READs</h2>");
  ASSERT_NE(no_reads, std::string::npos);
  EXPECT_LT(no_reads, html.find("<h2>Before and after</h2>"));
  // The object table: 20 rows, the other 30 folded under <details>.
  const auto objects = html.find("<h2>Objects</h2>");
  ASSERT_NE(objects, std::string::npos);
  const auto folded = html.find("<details><summary>30 more objects</summary>", objects);
  ASSERT_NE(folded, std::string::npos);
  int rows_before_fold = 0;
  for (auto at = html.find("<tr><td>", objects); at < folded; at = html.find("<tr><td>", at + 1))
    ++rows_before_fold;
  for (auto at = html.find("<tr class=\"noread\"><td>", objects); at < folded;
       at = html.find("<tr class=\"noread\"><td>", at + 1))
    ++rows_before_fold;
  EXPECT_EQ(rows_before_fold, 20);
  // Words, not keys: no summary key appears in the page.
  for (const char* key : {"object_read_rate", "frames_without_event", "latency_ms_p99",
                          "mean_decode_rate_per_object", "frames_captured"})
    EXPECT_EQ(html.find(key), std::string::npos) << key;
  EXPECT_NE(html.find("Latency, 99th percentile (ms)"), std::string::npos);
  EXPECT_NE(html.find("<td>96.0%</td>"), std::string::npos);  // the rate as a percentage
}

TEST(SessionReport, SaysWhichObjectsAreOnlyInTheLog) {
  testing::ScratchFolder scratch("report_omitted");
  ReportInputs in;
  in.summary = {{"objects", 1200u},
                {"objects_read", 1200u},
                {"object_read_rate", 1.0},
                {"frames_captured", 4000u},
                {"object_results_omitted", 700u}};
  for (std::uint64_t i = 701; i <= 1200; ++i) in.objects.push_back(object(i, "V"));
  ASSERT_EQ(write_report(scratch.path().string(), in), "");
  const std::string html = read_text(scratch.path() / "report.html");
  EXPECT_NE(html.find("The latest 500 objects; the 700 before them are in session.jsonl"),
            std::string::npos);
  EXPECT_NE(html.find("class=\"verdict good\""), std::string::npos);
  EXPECT_NE(html.find("Nothing went wrong"), std::string::npos);
  EXPECT_EQ(html.find("<h2>NO-READs</h2>"), std::string::npos);
}

}  // namespace
}  // namespace flutterscan::session
