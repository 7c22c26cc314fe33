// The live view (docs/session.md, "Live view"): the snapshot the results
// stage keeps (counters, flags, latency histogram, objects, NO-READs,
// pictures), its Prometheus text, --http addresses, the session-folder
// whitelist against traversal, and every endpoint of the server through
// cpp-httplib's client: content, read-only methods refused, traversal refused,
// a port in use; and a real sim session whose live figures end equal to its summary.
#include "session/live_view.hpp"

#include <gtest/gtest.h>
#include <httplib.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "session/live_view_server.hpp"
#include "session/session.hpp"
#include "session/test/session_test_support.hpp"

namespace flutterscan::session {
namespace {

namespace fs = std::filesystem;

FrameOutcome processed_frame(std::uint64_t index, double latency_ms, nlohmann::json flags) {
  FrameOutcome f;
  f.index = index;
  f.sequence = index;
  f.processed = true;
  f.latency_ms = latency_ms;
  f.log = {{"flags", std::move(flags)},
           {"decoded",
            {{{"text", "ABC-1"},
              {"format", "Code128"},
              {"corners", {{1, 2}, {30, 2}, {30, 9}, {1, 9}}}}}},
           {"decode_windows", 2}};
  return f;
}

ObjectResult object(std::uint64_t id, const std::string& value, int seen, int decoded) {
  ObjectResult o;
  o.id = id;
  o.value = value;
  o.format = value.empty() ? "" : "Code128";
  o.frames_seen = seen;
  o.frames_decoded = decoded;
  o.best.frame.sequence = id * 10;
  if (value.empty()) o.best.frame.kept_frame = "frames/f" + std::string(7, '0') + "1.png";
  return o;
}

/// A view fed three frames (one dropped) and three objects (one NO-READ).
void feed(LiveView& view, Pipeline& pipeline) {
  pipeline.frames_captured = 3;
  pipeline.frames_processed = 2;
  pipeline.frames_dropped = 1;
  view.frame_done(processed_frame(0, 12, nlohmann::json::array()), pipeline);
  FrameOutcome drop;
  drop.index = 1;
  drop.log = {{"flags", {"dropped"}}};
  view.frame_done(drop, pipeline);
  view.frame_done(processed_frame(2, 60, {"no-read", "residual"}), pipeline);
  view.object_done(object(1, "ABC-1", 4, 3));
  view.object_done(object(2, "", 3, 0));
  view.object_done(object(3, "XYZ-9", 2, 2));
}

TEST(LiveView, StateCountsFramesFlagsLatencyAndObjects) {
  LiveView view;
  Pipeline pipeline(4);
  const auto before = view.state();
  EXPECT_EQ(before["state"], "starting");
  EXPECT_TRUE(before["picture"].is_null());
  view.begin("/tmp/session", {{"code", "seed-maxmin-1"}, {"controller", "virtual"}});
  feed(view, pipeline);
  const auto s = view.state();
  EXPECT_EQ(s["state"], "armed");
  EXPECT_EQ(s["line"]["code"], "seed-maxmin-1");
  EXPECT_EQ(s["frames"]["captured"], 3);
  EXPECT_EQ(s["frames"]["processed"], 2);
  EXPECT_EQ(s["frames"]["dropped"], 1);
  EXPECT_EQ(s["flags"]["dropped"], 1);
  EXPECT_EQ(s["flags"]["no-read"], 1);
  EXPECT_EQ(s["last_flags"], nlohmann::json({"no-read", "residual"}));
  EXPECT_DOUBLE_EQ(s["latency_ms"]["last"].get<double>(), 60);
  EXPECT_DOUBLE_EQ(s["latency_ms"]["p50"].get<double>(), 36);  // between 12 and 60
  EXPECT_EQ(s["objects"]["total"], 3);
  EXPECT_EQ(s["objects"]["read"], 2);
  EXPECT_EQ(s["objects"]["no_read"], 1);
  EXPECT_NEAR(s["objects"]["read_rate"].get<double>(), 2.0 / 3, 1e-4);
  EXPECT_NEAR(s["objects"]["mean_decode_rate"].get<double>(), (0.75 + 0 + 1) / 3, 1e-4);
  EXPECT_EQ(s["objects"]["last_minute"]["total"], 3);
  EXPECT_EQ(s["objects"]["last_minute"]["read"], 2);
  // Newest first, each the object's read record.
  ASSERT_EQ(s["recent_objects"].size(), 3u);
  EXPECT_EQ(s["recent_objects"][0]["object"], 3);
  EXPECT_EQ(s["recent_objects"][1]["status"], "NO-READ");
  ASSERT_EQ(s["no_reads"].size(), 1u);
  EXPECT_EQ(s["no_reads"][0]["frame_file"], "frames/f00000001.png");
  view.set_state("disarmed");
  EXPECT_EQ(view.state()["state"], "disarmed");
}

TEST(LiveView, RecentObjectsAndNoReadsStayBounded) {
  LiveView view;
  for (std::uint64_t i = 1; i <= 50; ++i) view.object_done(object(i, "", 1, 0));
  const auto s = view.state();
  EXPECT_EQ(s["objects"]["total"], 50);
  EXPECT_EQ(s["recent_objects"].size(), LiveView::kRecentObjects);
  EXPECT_EQ(s["no_reads"].size(), LiveView::kRecentNoReads);
  EXPECT_EQ(s["no_reads"][0]["object"], 50);
}

/// The value of the sample `name` (with its labels) in Prometheus text, or -1.
double sample(const std::string& text, const std::string& name) {
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(name + " ", 0) == 0) return std::stod(line.substr(name.size() + 1));
  return -1;
}

TEST(LiveView, MetricsAreCountersAndACumulativeLatencyHistogram) {
  LiveView view;
  Pipeline pipeline(4);
  feed(view, pipeline);
  const std::string m = view.metrics();
  EXPECT_NE(m.find("# TYPE flutterscan_frames_captured_total counter"), std::string::npos);
  EXPECT_NE(m.find("# TYPE flutterscan_frame_latency_seconds histogram"), std::string::npos);
  EXPECT_NE(m.find("# TYPE flutterscan_fps gauge"), std::string::npos);
  EXPECT_EQ(sample(m, "flutterscan_frames_captured_total"), 3);
  EXPECT_EQ(sample(m, "flutterscan_frames_processed_total"), 2);
  EXPECT_EQ(sample(m, "flutterscan_frames_dropped_total"), 1);
  EXPECT_EQ(sample(m, "flutterscan_reads_total"), 2);
  EXPECT_EQ(sample(m, "flutterscan_no_reads_total"), 1);
  EXPECT_EQ(sample(m, R"(flutterscan_frames_flagged_total{flag="residual"})"), 1);
  // 12 ms and 60 ms: buckets up to 10 ms hold none, 20 ms one, 75 ms and above both.
  EXPECT_EQ(sample(m, R"(flutterscan_frame_latency_seconds_bucket{le="0.01"})"), 0);
  EXPECT_EQ(sample(m, R"(flutterscan_frame_latency_seconds_bucket{le="0.02"})"), 1);
  EXPECT_EQ(sample(m, R"(flutterscan_frame_latency_seconds_bucket{le="0.05"})"), 1);
  EXPECT_EQ(sample(m, R"(flutterscan_frame_latency_seconds_bucket{le="0.075"})"), 2);
  EXPECT_EQ(sample(m, R"(flutterscan_frame_latency_seconds_bucket{le="+Inf"})"), 2);
  EXPECT_EQ(sample(m, "flutterscan_frame_latency_seconds_count"), 2);
  EXPECT_NEAR(sample(m, "flutterscan_frame_latency_seconds_sum"), 0.072, 1e-9);
}

/// A processed frame of `width` x `height` mono8 pixels and its fused latent.
FrameOutcome frame_with_pixels(std::uint64_t sequence, int width, int height) {
  FrameOutcome f = processed_frame(sequence, 10, nlohmann::json::array());
  f.frame.sequence = sequence;
  f.frame.format.width = width;
  f.frame.format.height = height;
  f.frame.format.pixel_format = capture::PixelFormat::kMono8;
  f.frame.data.assign(static_cast<std::size_t>(width * height), 90);
  f.latent = imaging::Plane(width, height, 0.5f);
  return f;
}

/// The width in a PNG's header (IHDR, big-endian at byte 16).
/// The width in a JPEG's start-of-frame segment (baseline or progressive), or -1.
int jpeg_width(const std::vector<std::uint8_t>& jpeg) {
  if (jpeg.size() < 4 || jpeg[0] != 0xFF || jpeg[1] != 0xD8) return -1;  // SOI
  for (std::size_t at = 2; at + 9 < jpeg.size();) {
    if (jpeg[at] != 0xFF) return -1;
    const int marker = jpeg[at + 1];
    if (marker == 0xC0 || marker == 0xC2) return (jpeg[at + 7] << 8) | jpeg[at + 8];
    at += 2 + static_cast<std::size_t>((jpeg[at + 2] << 8) | jpeg[at + 3]);
  }
  return -1;
}

TEST(LivePictures, ABayerMosaicIsThinnedByWholeCells) {
  LivePictures pictures(640);
  FrameOutcome f = frame_with_pixels(3, 1280, 40);
  f.frame.format.pixel_format = capture::PixelFormat::kBayerRggb8;
  pictures.encode(std::move(f.frame), std::move(f.latent), {});
  pictures.wait_idle();
  ASSERT_TRUE(pictures.latest());
  EXPECT_EQ(jpeg_width(pictures.latest()->captured_jpeg), 640);  // 2 of every 4 columns
  EXPECT_EQ(jpeg_width(pictures.latest()->fused_jpeg), 640);
  EXPECT_EQ(pictures.latest()->width, 1280);  // the codes' corners stay in the frame's pixels
}

TEST(LiveView, PicturesAreTakenAtMostOncePerIntervalAndEncodedOffThePath) {
  LiveView view(60'000);  // one picture a minute
  FrameOutcome first = frame_with_pixels(7, 1200, 90);
  view.offer_picture(first);
  EXPECT_TRUE(first.frame.data.empty());  // taken
  FrameOutcome second = frame_with_pixels(8, 1200, 90);
  view.offer_picture(second);
  EXPECT_FALSE(second.frame.data.empty());  // too soon: left as it was
  for (int i = 0; i < 500 && !view.picture(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  const auto picture = view.picture();
  ASSERT_TRUE(picture);
  EXPECT_EQ(picture->sequence, 7u);
  EXPECT_EQ(picture->width, 1200);
  // JPEG, thinned to every 2nd pixel (at most 640 wide), the latent averaged to the same size.
  EXPECT_EQ(jpeg_width(picture->captured_jpeg), 600);
  EXPECT_EQ(jpeg_width(picture->fused_jpeg), 600);
  EXPECT_EQ(picture->about["windows"], 2);
  EXPECT_EQ(view.state()["picture"]["sequence"], 7);
}

TEST(LivePictures, TheLastThreeAreKeptForThePageToAskBySequence) {
  LivePictures pictures(64);
  for (std::uint64_t sequence = 1; sequence <= 4; ++sequence) {
    FrameOutcome f = frame_with_pixels(sequence, 100, 40);
    pictures.encode(std::move(f.frame), std::move(f.latent), {});
    pictures.wait_idle();
  }
  EXPECT_EQ(pictures.encoded(), 4u);
  EXPECT_EQ(pictures.latest()->sequence, 4u);
  EXPECT_FALSE(pictures.of_frame(1));
  for (std::uint64_t sequence = 2; sequence <= 4; ++sequence) {
    ASSERT_TRUE(pictures.of_frame(sequence));
    EXPECT_EQ(pictures.of_frame(sequence)->sequence, sequence);
  }
}

TEST(LiveViewAddress, ParsesAddressPortAndOff) {
  auto off = parse_http_address("off");
  ASSERT_TRUE(off.ok());
  EXPECT_FALSE(off.value());
  auto v4 = parse_http_address("127.0.0.1:8090");
  ASSERT_TRUE(v4.ok() && v4.value());
  EXPECT_EQ(v4.value()->host, "127.0.0.1");
  EXPECT_EQ(v4.value()->port, 8090);
  auto v6 = parse_http_address("[::1]:0");
  ASSERT_TRUE(v6.ok() && v6.value());
  EXPECT_EQ(v6.value()->host, "::1");
  EXPECT_EQ(v6.value()->port, 0);
  for (const char* bad : {"8090", "localhost", ":8090", "host:", "::1:8090", "host:70000",
                          "host:80a", "[]:80", "[::1:80"}) {
    auto r = parse_http_address(bad);
    EXPECT_FALSE(r.ok()) << bad;
    if (!r.ok()) {
      EXPECT_NE(r.error().find(bad), std::string::npos) << r.error();
    }
  }
  EXPECT_TRUE(is_loopback("127.0.0.1"));
  EXPECT_TRUE(is_loopback("127.1.2.3"));
  EXPECT_TRUE(is_loopback("::1"));
  EXPECT_TRUE(is_loopback("localhost"));
  EXPECT_FALSE(is_loopback("0.0.0.0"));
  EXPECT_FALSE(is_loopback("::"));
  EXPECT_FALSE(is_loopback("192.0.2.7"));
}

/// A session folder with its files, a secret beside it and a symlink to the secret inside it.
struct FolderWithSecret {
  testing::ScratchFolder scratch{"live_view_files"};
  fs::path folder = scratch.path() / "session";
  fs::path secret = scratch.path() / "secret.txt";
  FolderWithSecret() {
    fs::create_directories(folder / "frames");
    std::ofstream(folder / "summary.json") << R"({"frames_processed": 3})";
    std::ofstream(folder / "session.jsonl") << "{}\n";
    std::ofstream(folder / "frames" / "f00000001.png") << "raw";
    std::ofstream(folder / "frames" / "f00000001.fused.png") << "fused";
    std::ofstream(secret) << "SECRET";
    fs::create_symlink(secret, folder / "frames" / "f00000002.png");
    fs::create_symlink(secret, folder / "report.html");
  }
};

TEST(LiveViewFiles, OnlyTheWhitelistInsideTheFolderIsServed) {
  const FolderWithSecret f;
  const std::string folder = f.folder.string();
  EXPECT_EQ(session_file(folder, "summary.json"), f.folder / "summary.json");
  EXPECT_EQ(session_file(folder, "frames/f00000001.png"), f.folder / "frames/f00000001.png");
  EXPECT_TRUE(session_file(folder, "frames/f00000001.fused.png"));
  for (const std::string& name : std::vector<std::string>{
           "../secret.txt", "frames/../../secret.txt", "frames/../summary.json", "./summary.json",
           f.secret.string(), "/etc/passwd", "session.jsonl", "frames/f00000002.png" /* symlink */,
           "report.html" /* symlink */, "frames/f00000003.png" /* missing */, "frames", "",
           "summary.json/", "frames//f00000001.png", "frames/f1.png"})
    EXPECT_FALSE(session_file(folder, name)) << name;
  EXPECT_FALSE(session_file("", "summary.json"));  // no session yet
}

TEST(LiveViewFiles, AFramesFolderThatIsASymlinkIsRefused) {
  const FolderWithSecret f;
  const fs::path other = f.scratch.path() / "other";
  fs::create_directories(other / "frames");
  std::ofstream(other / "frames" / "f00000001.png") << "elsewhere";
  fs::create_directories(other / "session");
  fs::create_symlink(other / "frames", other / "session" / "frames");
  EXPECT_FALSE(session_file((other / "session").string(), "frames/f00000001.png"));
}

/// A server on a free loopback port, serving `view`.
struct Served {
  explicit Served(LiveView& view) : server(view) {
    problem = server.listen({"127.0.0.1", 0});
    client = std::make_unique<httplib::Client>("127.0.0.1", server.port());
    client->set_url_encode(false);  // the paths exactly as written here
  }
  LiveViewServer server;
  std::string problem;
  std::unique_ptr<httplib::Client> client;
};

TEST(LiveViewServer, ServesThePageStateMetricsPicturesAndFiles) {
  const FolderWithSecret f;
  LiveView view;
  Pipeline pipeline(4);
  Served served(view);
  ASSERT_EQ(served.problem, "");
  ASSERT_GT(served.server.port(), 0);
  httplib::Client& client = *served.client;

  auto page = client.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_EQ(page->get_header_value("Content-Type"), "text/html; charset=utf-8");
  EXPECT_NE(page->body.find("flutterscan live view"), std::string::npos);
  EXPECT_NE(page->get_header_value("Content-Security-Policy").find("default-src 'none'"),
            std::string::npos);
  // No external resource: nothing loaded from another host (the one http:// is SVG's namespace).
  EXPECT_EQ(page->body.find("src=\"http"), std::string::npos);
  EXPECT_EQ(page->body.find("href=\"http"), std::string::npos);
  EXPECT_EQ(page->body.find("url("), std::string::npos);
  EXPECT_EQ(page->body.find("https://"), std::string::npos);

  auto none = client.Get("/frame/fused.jpg");
  ASSERT_TRUE(none);
  EXPECT_EQ(none->status, 404);  // no picture yet

  view.begin(f.folder.string(), {{"code", "seed-maxmin-1"}});
  feed(view, pipeline);
  FrameOutcome pictured = frame_with_pixels(5, 320, 80);
  view.offer_picture(pictured);
  for (int i = 0; i < 500 && !view.picture(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));

  auto state = client.Get("/state.json");
  ASSERT_TRUE(state);
  EXPECT_EQ(state->status, 200);
  EXPECT_EQ(state->get_header_value("Content-Type"), "application/json");
  EXPECT_EQ(state->get_header_value("Cache-Control"), "no-store");
  const auto s = nlohmann::json::parse(state->body);
  EXPECT_EQ(s["frames"]["processed"], 2);
  EXPECT_EQ(s["objects"]["read"], 2);
  EXPECT_EQ(s["picture"]["sequence"], 5);

  auto metrics = client.Get("/metrics");
  ASSERT_TRUE(metrics);
  EXPECT_EQ(metrics->status, 200);
  EXPECT_EQ(metrics->get_header_value("Content-Type"), "text/plain; version=0.0.4; charset=utf-8");
  EXPECT_EQ(sample(metrics->body, "flutterscan_reads_total"), 2);

  for (const char* path : {"/frame/captured.jpg", "/frame/fused.jpg?frame=5"}) {
    auto jpeg = client.Get(path);
    ASSERT_TRUE(jpeg) << path;
    EXPECT_EQ(jpeg->status, 200) << path;
    EXPECT_EQ(jpeg->get_header_value("Content-Type"), "image/jpeg");
    EXPECT_EQ(jpeg->body.substr(0, 2), "\xFF\xD8") << path;  // JPEG's start of image
  }
  auto gone = client.Get("/frame/fused.jpg?frame=4");  // not among the last pictures
  ASSERT_TRUE(gone);
  EXPECT_EQ(gone->status, 404);
  auto summary = client.Get("/files/summary.json");
  ASSERT_TRUE(summary);
  EXPECT_EQ(summary->status, 200);
  EXPECT_EQ(summary->body, R"({"frames_processed": 3})");
  auto kept = client.Get("/files/frames/f00000001.fused.png");
  ASSERT_TRUE(kept);
  EXPECT_EQ(kept->status, 200);
  EXPECT_EQ(kept->body, "fused");
  auto head = client.Head("/state.json");
  ASSERT_TRUE(head);
  EXPECT_EQ(head->status, 200);
}

TEST(LiveViewServer, TraversalAndFilesOutsideTheWhitelistAreRefused) {
  const FolderWithSecret f;
  LiveView view;
  view.begin(f.folder.string(), {});
  Served served(view);
  ASSERT_EQ(served.problem, "");
  const std::string absolute = f.secret.string();
  for (const std::string& path : std::vector<std::string>{
           "/files/../secret.txt", "/files/%2e%2e/secret.txt", "/files/%2E%2E%2Fsecret.txt",
           "/files/frames/%2e%2e/%2e%2e/secret.txt", "/files/frames/..%2f..%2fsecret.txt",
           "/files/" + absolute, "/files/%2F" + absolute.substr(1), "/files//etc/passwd",
           "/files/frames/f00000002.png", "/files/report.html", "/files/session.jsonl",
           "/../secret.txt", "/%2e%2e/secret.txt", "/files/summary.json%00.png"}) {
    auto r = served.client->Get(path);
    ASSERT_TRUE(r) << path;
    EXPECT_NE(r->status, 200) << path;
    EXPECT_EQ(r->body.find("SECRET"), std::string::npos) << path;
  }
}

TEST(LiveViewServer, IsReadOnly) {
  const FolderWithSecret f;
  LiveView view;
  view.begin(f.folder.string(), {});
  Served served(view);
  ASSERT_EQ(served.problem, "");
  httplib::Client& client = *served.client;
  for (const char* path : {"/", "/state.json", "/metrics", "/files/summary.json"}) {
    auto post = client.Post(path, "stop", "text/plain");
    ASSERT_TRUE(post) << path;
    EXPECT_EQ(post->status, 405) << path;
    EXPECT_EQ(post->get_header_value("Allow"), "GET, HEAD");
    auto put = client.Put(path, "{}", "application/json");
    ASSERT_TRUE(put) << path;
    EXPECT_EQ(put->status, 405) << path;
    auto del = client.Delete(path);
    ASSERT_TRUE(del) << path;
    EXPECT_EQ(del->status, 405) << path;
    auto patch = client.Patch(path, "{}", "application/json");
    ASSERT_TRUE(patch) << path;
    EXPECT_EQ(patch->status, 405) << path;
  }
  EXPECT_TRUE(fs::exists(f.folder / "summary.json"));
  EXPECT_EQ(view.state()["state"], "armed");
}

TEST(LiveViewServer, APortInUseIsAClearError) {
  LiveView view;
  Served first(view);
  ASSERT_EQ(first.problem, "");
  LiveViewServer second(view);
  const std::string problem = second.listen({"127.0.0.1", first.server.port()});
  EXPECT_NE(problem.find("127.0.0.1:" + std::to_string(first.server.port())), std::string::npos)
      << problem;
  EXPECT_NE(problem.find("in use"), std::string::npos) << problem;
  second.stop();  // never listened: returns
}

TEST(LiveViewSession, TheLiveFiguresEndEqualToTheSummary) {
  testing::ScratchFolder scratch("live_view_session");
  LiveView view;
  Served served(view);
  ASSERT_EQ(served.problem, "");
  SessionHooks hooks;
  hooks.live_view = &view;
  std::atomic<bool> stop{false};
  const SessionOutcome outcome =
      run_session(testing::small_sim_config(scratch.path(), 60), stop, hooks);
  ASSERT_EQ(outcome.error, "");
  auto r = served.client->Get("/state.json");
  ASSERT_TRUE(r);
  const auto s = nlohmann::json::parse(r->body);
  const auto& summary = outcome.summary;
  EXPECT_EQ(s["state"], "disarmed");
  EXPECT_EQ(s["folder"], outcome.folder);
  EXPECT_EQ(s["line"]["code"], summary["code"]);
  EXPECT_EQ(s["line"]["method"], summary["method"]);  // "cascade" by default, as run
  EXPECT_EQ(s["frames"]["captured"], summary["frames_captured"]);
  EXPECT_EQ(s["frames"]["processed"], summary["frames_processed"]);
  EXPECT_EQ(s["frames"]["dropped"], summary["frames_dropped"]);
  EXPECT_EQ(s["frames"]["failed"], summary["frames_failed"]);
  EXPECT_EQ(s["objects"]["total"], summary["objects"]);
  EXPECT_EQ(s["objects"]["read"], summary["objects_read"]);
  EXPECT_NEAR(s["objects"]["read_rate"].get<double>(), summary["object_read_rate"].get<double>(),
              1e-4);
  EXPECT_NEAR(s["objects"]["mean_decode_rate"].get<double>(),
              summary["mean_decode_rate_per_object"].get<double>(), 1e-4);
  EXPECT_GT(s["objects"]["read"].get<int>(), 0);
  EXPECT_FALSE(s["picture"].is_null());
  auto summary_file = served.client->Get("/files/summary.json");
  ASSERT_TRUE(summary_file);
  EXPECT_EQ(summary_file->status, 200);
  EXPECT_EQ(nlohmann::json::parse(summary_file->body)["frames_processed"],
            summary["frames_processed"]);
}

}  // namespace
}  // namespace flutterscan::session
