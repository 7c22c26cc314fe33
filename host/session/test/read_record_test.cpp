// The read record: an object's best sighting is the best-graded read of the
// value it reports (a NO-READ's is its last sighting), and the record carries
// the version 1 fields unchanged with the record's beside them.
#include "session/read_record.hpp"

#include <gtest/gtest.h>

#include "session/object_tracker.hpp"

namespace flutterscan::session {
namespace {

Sighting read(double position, const std::string& value, double grade_value,
              std::uint64_t sequence) {
  Sighting s;
  s.position_px = position;
  s.across_px = 120;
  s.decoded = true;
  s.value = value;
  s.format = "Code128";
  s.code.text = value;
  s.code.format = "Code128";
  s.code.symbology_id = "]C0";
  s.code.orientation_deg = 90;
  s.code.quality.measured = true;
  s.code.quality.grade_value = grade_value;
  s.code.quality.grade = reader::grade_letter(grade_value);
  s.code.quality.module_px = 2.5;
  s.code.quality.corners = {{{10, 20}, {110, 20}, {110, 60}, {10, 60}}};
  s.frame.sequence = sequence;
  s.frame.utc_ms = 1'795'000'000'123;
  s.frame.exposure_counter = static_cast<std::uint32_t>(sequence + 1000);
  s.frame.decode_ms = 3.25;
  s.frame.blur_px = 52;
  return s;
}

Sighting missed(double position, std::uint64_t sequence) {
  Sighting s;
  s.position_px = position;
  s.frame.sequence = sequence;
  s.frame.kept_frame = "frames/f" + std::to_string(sequence) + ".png";
  return s;
}

TEST(ObjectTracker, TheBestSightingIsTheBestGradedReadOfTheValueReported) {
  ObjectTracker tracker(1000, 30);
  tracker.observe(0, 10, 0, {read(100, "FS-1", 2.0, 10)});
  tracker.observe(1, 11, 50, {read(150, "FS-1", 3.6, 11)});
  tracker.observe(2, 12, 100, {read(200, "FS-X", 4.0, 12)});  // a stray value, graded better
  tracker.observe(3, 13, 150, {read(250, "FS-1", 3.6, 13)});  // as good as frame 11: not better
  const auto objects = tracker.finish_all();
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(objects[0].value, "FS-1");
  EXPECT_EQ(objects[0].best.frame.sequence, 11u);
  EXPECT_EQ(objects[0].best.value, "FS-1");
}

TEST(ObjectTracker, ANoReadReportsItsLastSighting) {
  ObjectTracker tracker(1000, 30);
  tracker.observe(0, 20, 0, {missed(100, 20)});
  tracker.observe(1, 21, 50, {missed(150, 21)});
  const auto objects = tracker.finish_all();
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_FALSE(objects[0].read());
  EXPECT_EQ(objects[0].best.frame.sequence, 21u);
}

TEST(ReadRecord, AReadCarriesTheVersion1FieldsAndTheRecord) {
  ObjectTracker tracker(1000, 30);
  Sighting s = read(400, "FS-7", 3.6, 42);
  s.frame.travel_px = 300;
  s.frame.encoder_blur_px = 52.0;
  s.frame.refined_blur_px = 51.63;
  tracker.observe(0, 42, 300, {s});
  const nlohmann::json r = read_record(tracker.finish_all().at(0));
  // Version 1.
  EXPECT_EQ(r["object"], 1);
  EXPECT_EQ(r["status"], "READ");
  EXPECT_EQ(r["value"], "FS-7");
  EXPECT_EQ(r["format"], "Code128");
  EXPECT_EQ(r["frames"], 1);
  // The record.
  EXPECT_EQ(r["time"], iso8601_utc(1'795'000'000'123));
  EXPECT_EQ(r["sequence"], 42);
  EXPECT_EQ(r["trigger"]["exposure_counter"], 1042);
  EXPECT_EQ(r["symbology_id"], "]C0");
  EXPECT_EQ(r["corners"], nlohmann::json::parse("[[10,20],[110,20],[110,60],[10,60]]"));
  EXPECT_EQ(r["orientation_deg"], 90);
  EXPECT_EQ(r["centre_belt_px"], nlohmann::json::parse("[100.0,120.0]"));
  EXPECT_EQ(r["module_px"], 2.5);
  EXPECT_EQ(r["quality"]["grade"], "A");
  EXPECT_EQ(r["quality"]["indicative"], true);
  EXPECT_EQ(r["blur_px"], 52);
  EXPECT_EQ(r["motion"]["refined_blur_px"], 51.63);
  EXPECT_EQ(r["decode_ms"], 3.25);
  EXPECT_FALSE(r.contains("frame_file"));
}

TEST(ReadRecord, ANoReadCarriesItsFrameAndTheKeptFile) {
  ObjectTracker tracker(1000, 30);
  tracker.observe(0, 7, 0, {missed(100, 7)});
  const nlohmann::json r = read_record(tracker.finish_all().at(0));
  EXPECT_EQ(r["status"], "NO-READ");
  EXPECT_EQ(r["sequence"], 7);
  EXPECT_EQ(r["frame_file"], "frames/f7.png");
  EXPECT_FALSE(r.contains("symbology_id"));
  EXPECT_FALSE(r.contains("value"));
}

TEST(ReadRecord, TimesAreIso8601UtcWithMilliseconds) {
  EXPECT_EQ(iso8601_utc(0), "1970-01-01T00:00:00.000Z");
  EXPECT_EQ(iso8601_utc(1'795'000'000'123), "2026-11-18T11:06:40.123Z");
  EXPECT_EQ(iso8601_utc(-1), "1969-12-31T23:59:59.999Z");
}

}  // namespace
}  // namespace flutterscan::session
