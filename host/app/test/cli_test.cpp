// End-to-end tests of the real `flutterscan` binary: each test runs it as a
// child process (fork + execv, argv passed directly, no shell) with stdout and
// stderr captured to files in a per-test temporary directory, then checks the
// exit code (0 success, 1 runtime failure, 2 bad usage or input), the output
// and the files written.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <ostream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// ---------------------------------------------------------------------------
// Running the binary

/// \brief What one run of the binary gave back.
struct RunResult {
  int exit_code = -1;  ///< the exit status; 128 + N when killed by signal N
  std::string out;     ///< everything written to stdout
  std::string err;     ///< everything written to stderr
};

std::ostream& operator<<(std::ostream& stream, const RunResult& result) {
  return stream << "exit code " << result.exit_code << "\n--- stdout ---\n"
                << result.out.substr(0, 2000) << "\n--- stderr ---\n"
                << result.err.substr(0, 2000) << "\n";
}

std::string read_file(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>()};
}

/// \brief Runs FLUTTERSCAN_BINARY with `args` (argv[1...]), capturing stdout and
/// stderr into files under `scratch`. The child gets an alarm so that a hung
/// binary fails the test instead of the whole suite.
RunResult run_binary(const std::vector<std::string>& args, const fs::path& scratch) {
  static int serial = 0;
  ++serial;
  const fs::path out_path = scratch / ("stdout-" + std::to_string(serial));
  const fs::path err_path = scratch / ("stderr-" + std::to_string(serial));

  std::vector<std::string> storage;
  storage.reserve(args.size() + 1);
  storage.emplace_back(FLUTTERSCAN_BINARY);
  storage.insert(storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& arg : storage) argv.push_back(arg.data());
  argv.push_back(nullptr);

  RunResult result;
  const int out_fd = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  const int err_fd = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (out_fd < 0 || err_fd < 0) {
    ADD_FAILURE() << "cannot create capture files in " << scratch << ": " << std::strerror(errno);
    if (out_fd >= 0) ::close(out_fd);
    if (err_fd >= 0) ::close(err_fd);
    return result;
  }
  const int null_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);

  const pid_t pid = ::fork();
  if (pid == 0) {
    // Child: only async-signal-safe calls until execv.
    if (null_fd >= 0) ::dup2(null_fd, STDIN_FILENO);
    ::dup2(out_fd, STDOUT_FILENO);
    ::dup2(err_fd, STDERR_FILENO);
    ::alarm(120);  // survives execv: SIGALRM ends a hung child
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ::close(out_fd);
  ::close(err_fd);
  if (null_fd >= 0) ::close(null_fd);
  if (pid < 0) {
    ADD_FAILURE() << "fork failed: " << std::strerror(errno);
    return result;
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      ADD_FAILURE() << "waitpid failed: " << std::strerror(errno);
      return result;
    }
  }
  if (WIFEXITED(status))
    result.exit_code = WEXITSTATUS(status);
  else if (WIFSIGNALED(status))
    result.exit_code = 128 + WTERMSIG(status);
  result.out = read_file(out_path);
  result.err = read_file(err_path);
  return result;
}

/// \brief stdout split into lines; every line must end with '\n'.
std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = text.find('\n', start);
    if (end == std::string::npos) {
      ADD_FAILURE() << "output does not end with a newline: " << text.substr(start, 200);
      lines.push_back(text.substr(start));
      break;
    }
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return lines;
}

/// \brief Every line of stdout parsed as one JSON object (a failure on any other line).
std::vector<json> json_lines(const std::string& text) {
  std::vector<json> objects;
  for (const auto& line : lines_of(text)) {
    json object = json::parse(line, nullptr, /*allow_exceptions=*/false);
    EXPECT_FALSE(object.is_discarded()) << "not JSON: " << line.substr(0, 200);
    EXPECT_TRUE(object.is_object()) << "not a JSON object: " << line.substr(0, 200);
    objects.push_back(std::move(object));
  }
  return objects;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

/// \brief The digit string is a one-of-3 code of `length` slots (digits 1, 2, 4 only).
void expect_one_of_3(const std::string& code, std::size_t length) {
  EXPECT_EQ(code.size(), length) << code;
  EXPECT_EQ(code.find_first_not_of("124"), std::string::npos)
      << "not a one-of-3 code (digits 1, 2, 4 only): " << code;
}

constexpr const char* kSeedMaxMin1 = "2212441414112412441224111241244244242212442211444144";

// ---------------------------------------------------------------------------
// Fixture: a fresh temporary directory per test

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const char* base = std::getenv("TMPDIR");
    std::string pattern = std::string(base && *base ? base : "/tmp") + "/flutterscan-cli-XXXXXX";
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr) << "mkdtemp: " << std::strerror(errno);
    dir_ = pattern;
  }

  void TearDown() override {
    std::error_code ignored;
    if (!dir_.empty()) fs::remove_all(dir_, ignored);
  }

  RunResult run(const std::vector<std::string>& args) { return run_binary(args, dir_); }

  /// \brief Bad usage or input: exit 2, nothing on stdout, and stderr holds every
  /// one of `needles` (the message names what is wrong and where).
  void expect_usage_error(const std::vector<std::string>& args,
                          const std::vector<std::string>& needles) {
    std::string command;
    for (const auto& arg : args) command += " '" + arg.substr(0, 60) + "'";
    SCOPED_TRACE("flutterscan" + command);
    const RunResult result = run(args);
    EXPECT_EQ(result.exit_code, 2) << result;
    EXPECT_TRUE(result.out.empty()) << result;
    EXPECT_FALSE(result.err.empty()) << result;
    for (const auto& needle : needles)
      EXPECT_TRUE(contains(result.err, needle)) << "stderr lacks \"" << needle << "\"\n" << result;
  }

  /// \brief A successful search: exit 0, one JSON line, returned parsed.
  json search_json(const std::vector<std::string>& options) {
    std::vector<std::string> args{"codes", "search"};
    args.insert(args.end(), options.begin(), options.end());
    args.emplace_back("--json");
    const RunResult result = run(args);
    EXPECT_EQ(result.exit_code, 0) << result;
    const auto objects = json_lines(result.out);
    EXPECT_EQ(objects.size(), 1U) << result;
    return objects.empty() ? json::object() : objects.front();
  }

  fs::path dir_;
};

// ---------------------------------------------------------------------------
// codes score

TEST_F(CliTest, ScoreSeedCodeJsonHasTheSeedsMaxMinAndPerLedCounts) {
  const RunResult result = run({"codes", "score", kSeedMaxMin1, "--json"});
  ASSERT_EQ(result.exit_code, 0) << result;
  EXPECT_TRUE(result.err.empty()) << result;
  const auto objects = json_lines(result.out);
  ASSERT_EQ(objects.size(), 1U) << result;
  const json& report = objects.front();

  EXPECT_EQ(report.at("code"), kSeedMaxMin1);
  ASSERT_TRUE(report.at("merits").at("maxmin").is_number()) << report.dump();
  EXPECT_NEAR(report["merits"]["maxmin"].get<double>(), -21.4382, 5e-5);
  EXPECT_TRUE(report["merits"].contains("single"));
  EXPECT_TRUE(report["merits"]["single"].is_null()) << "single is for one-LED codes";

  const json& per_led = report.at("per_led");
  ASSERT_TRUE(per_led.is_array());
  ASSERT_EQ(per_led.size(), 3U);
  int on_slots = 0;
  for (const auto& led : per_led) on_slots += led.at("on_slots").get<int>();
  EXPECT_EQ(on_slots, 52) << "a one-of-3 code has exactly one LED on in each of its 52 slots";
}

TEST_F(CliTest, ScoreTwoCodesGiveTwoJsonLinesInOrder) {
  const RunResult result = run({"codes", "score", kSeedMaxMin1, "raskar", "--json"});
  ASSERT_EQ(result.exit_code, 0) << result;
  const auto objects = json_lines(result.out);
  ASSERT_EQ(objects.size(), 2U) << result;
  EXPECT_EQ(objects[0].at("code"), kSeedMaxMin1);
  EXPECT_EQ(objects[1].at("name"), "raskar");
  EXPECT_EQ(objects[1].at("code"), "1010000111000001010000110011110111010111001001100111");
}

TEST_F(CliTest, ScoreRaskarJson) {
  const RunResult result = run({"codes", "score", "raskar", "--json"});
  ASSERT_EQ(result.exit_code, 0) << result;
  const auto objects = json_lines(result.out);
  ASSERT_EQ(objects.size(), 1U) << result;
  const json& merits = objects.front().at("merits");
  ASSERT_TRUE(merits.at("maxmin").is_number()) << merits.dump();
  EXPECT_NEAR(merits["maxmin"].get<double>(), -25.4359, 5e-5);
  EXPECT_TRUE(merits.contains("pairs"));
  EXPECT_TRUE(merits["pairs"].is_null()) << "pairs needs several LEDs; raskar has one";
  ASSERT_TRUE(merits.at("single").is_number()) << merits.dump();
  EXPECT_GT(merits["single"].get<double>(), 0.0);
  EXPECT_EQ(objects.front().at("leds"), 1);
}

TEST_F(CliTest, ScoreTextOutputNamesTheCode) {
  const RunResult result = run({"codes", "score", "raskar"});
  ASSERT_EQ(result.exit_code, 0) << result;
  EXPECT_TRUE(contains(result.out, "raskar")) << result;
  EXPECT_TRUE(contains(result.out, "-25.4359")) << result;
}

// ---------------------------------------------------------------------------
// Bad input: exit 2, nothing on stdout, stderr names what and where

TEST_F(CliTest, NonDigitInCodeNamesSlotAndCharacter) {
  expect_usage_error({"codes", "score", "1212x4"}, {"1212x4", "slot 4", "'x'"});
}

TEST_F(CliTest, DigitLightingAMissingLedNamesTheSlot) {
  expect_usage_error({"codes", "score", "12184"}, {"12184", "slot 3"});
}

TEST_F(CliTest, OneOfNRejectsADigitLightingTwoLeds) {
  expect_usage_error({"codes", "score", "--one-of-n", "1213"},
                     {"slot 3: digit 3 lights two LEDs in a one-of-3 code"});
}

TEST_F(CliTest, EmptyCodeIsRejected) {
  expect_usage_error({"codes", "score", ""}, {"empty"});
}

TEST_F(CliTest, TooLongCodeIsRejected) {
  expect_usage_error({"codes", "score", std::string(257, '1')}, {"257 slots"});
  // 256 slots is the limit itself and is fine.
  const RunResult result = run({"codes", "score", std::string(256, '1'), "--merit", "maxmin"});
  EXPECT_EQ(result.exit_code, 0) << result;
}

TEST_F(CliTest, UnknownMeritIsNamed) {
  expect_usage_error({"codes", "score", "raskar", "--merit", "foo"}, {"unknown merit 'foo'"});
  expect_usage_error({"codes", "search", "--merit", "foo", "--evaluations", "100"},
                     {"unknown merit 'foo'"});
}

TEST_F(CliTest, BadCrosstalkEntryNamesRowAndColumn) {
  expect_usage_error({"codes", "score", kSeedMaxMin1, "--merit", "joint", "--crosstalk", "1,0;0,x"},
                     {"--crosstalk", "row 1, column 1"});
}

TEST_F(CliTest, NegativeElectronsIsRejected) {
  expect_usage_error({"codes", "score", "raskar", "--electrons", "-5"}, {"--electrons"});
}

TEST_F(CliTest, SearchWithBothBudgetsIsRejected) {
  expect_usage_error(
      {"codes", "search", "--merit", "maxmin", "--seconds", "1", "--evaluations", "1000"},
      {"--seconds", "--evaluations"});
}

TEST_F(CliTest, SearchWithoutABudgetIsRejected) {
  const RunResult result = run({"codes", "search", "--merit", "maxmin"});
  EXPECT_EQ(result.exit_code, 2) << result;
  EXPECT_TRUE(result.out.empty()) << result;
  EXPECT_TRUE(contains(result.err, "--seconds") || contains(result.err, "--evaluations")) << result;
}

TEST_F(CliTest, PairsSearchOfOneLedIsRejected) {
  expect_usage_error(
      {"codes", "search", "--merit", "pairs", "--leds", "1", "--evaluations", "1000"}, {"pairs"});
}

TEST_F(CliTest, MissingOrUnknownSubcommandIsBadUsage) {
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"codes"}, std::vector<std::string>{"codes", "frob"},
        std::vector<std::string>{}, std::vector<std::string>{"frob"}}) {
    std::string command;
    for (const auto& arg : args) command += " " + arg;
    SCOPED_TRACE("flutterscan" + command);
    const RunResult result = run(args);
    EXPECT_EQ(result.exit_code, 2) << result;
    EXPECT_TRUE(result.out.empty()) << result;
    EXPECT_FALSE(result.err.empty()) << result;
  }
}

// The error message should name the word it did not understand, like every
// other usage error does.
TEST_F(CliTest, UnknownSubcommandIsNamedInTheMessage) {
  expect_usage_error({"codes", "frob"}, {"frob"});
}

TEST_F(CliTest, ALaterBadCodePrintsNothing) {
  // Every argument is parsed before anything is printed.
  expect_usage_error({"codes", "score", "raskar", kSeedMaxMin1, "12184", "--json"},
                     {"12184", "slot 3"});
  expect_usage_error({"codes", "score", "raskar", "1212x4"}, {"1212x4", "slot 4"});
}

// ---------------------------------------------------------------------------
// codes search

TEST_F(CliTest, AnnealSearchIsDeterministicWithASeed) {
  const std::vector<std::string> options{"--merit", "maxmin", "--evaluations",
                                         "300000",  "--seed", "5"};
  const json first = search_json(options);
  const json second = search_json(options);
  ASSERT_TRUE(first.contains("code") && second.contains("code"));
  EXPECT_EQ(first["code"], second["code"]) << "same --seed and --evaluations, same code";
  expect_one_of_3(first["code"].get<std::string>(), 52);
  ASSERT_TRUE(first.contains("search"));
  EXPECT_EQ(first["search"].at("evaluations"), 300000);
  EXPECT_EQ(first["search"].at("merit"), "maxmin");
  EXPECT_EQ(first["search"].at("seed"), 5);

  // Another seed must also work (its code is allowed to match or differ).
  const json other = search_json({"--merit", "maxmin", "--evaluations", "300000", "--seed", "6"});
  ASSERT_TRUE(other.contains("code"));
  expect_one_of_3(other["code"].get<std::string>(), 52);
  EXPECT_EQ(other["search"].at("evaluations"), 300000);
}

TEST_F(CliTest, GeneticSearchIsDeterministicAndItsSelectionIsWeak) {
  const std::vector<std::string> options{"--algorithm", "genetic", "--evaluations",
                                         "20000",       "--seed",  "5"};
  const json first = search_json(options);
  const json second = search_json(options);
  ASSERT_TRUE(first.contains("code") && second.contains("code"));
  EXPECT_EQ(first["code"], second["code"]);
  expect_one_of_3(first["code"].get<std::string>(), 52);
  ASSERT_TRUE(first.contains("search"));
  EXPECT_EQ(first["search"].at("evaluations"), 20000);
  EXPECT_EQ(first["search"].at("algorithm"), "genetic");
  ASSERT_TRUE(first["search"].contains("mean_selection_pressure")) << first["search"].dump();
  const double pressure = first["search"]["mean_selection_pressure"].get<double>();
  // The seed's roulette on 1000 + score barely favours the best.
  EXPECT_GE(pressure, 1.0);
  EXPECT_LE(pressure, 1.1);
}

TEST_F(CliTest, BalancedSearchGives17And18And17OnSlots) {
  const json found = search_json(
      {"--leds", "3", "--balanced", "--merit", "joint", "--evaluations", "100000", "--seed", "2"});
  ASSERT_TRUE(found.contains("per_led")) << found.dump();
  std::vector<int> counts;
  for (const auto& led : found["per_led"]) counts.push_back(led.at("on_slots").get<int>());
  std::sort(counts.begin(), counts.end());
  EXPECT_EQ(counts, (std::vector<int>{17, 17, 18}));
  expect_one_of_3(found.at("code").get<std::string>(), 52);
}

TEST_F(CliTest, SingleLedSearchWithOnesGivesThatManyOnes) {
  const json found = search_json({"--leds", "1", "--merit", "single", "--ones", "26",
                                  "--evaluations", "100000", "--seed", "2"});
  ASSERT_TRUE(found.contains("code")) << found.dump();
  const std::string code = found["code"].get<std::string>();
  EXPECT_EQ(code.size(), 52U) << code;
  EXPECT_EQ(code.find_first_not_of("01"), std::string::npos) << code;
  EXPECT_EQ(std::count(code.begin(), code.end(), '1'), 26) << code;
  EXPECT_EQ(found.at("leds"), 1);
  ASSERT_TRUE(found.at("merits").at("single").is_number());
  EXPECT_GT(found["merits"]["single"].get<double>(), 0.0);
}

// ---------------------------------------------------------------------------
// codes plot

TEST_F(CliTest, PlotWritesAPng) {
  const fs::path png = dir_ / "s.png";
  const RunResult result = run({"codes", "plot", "raskar", "seed-maxmin-1", "-o", png.string()});
  ASSERT_EQ(result.exit_code, 0) << result;
  ASSERT_TRUE(fs::exists(png)) << result;
  const std::string bytes = read_file(png);
  const std::string signature("\x89PNG\r\n\x1a\n", 8);
  ASSERT_GE(bytes.size(), signature.size());
  EXPECT_EQ(bytes.substr(0, 8), signature);
  EXPECT_GT(bytes.size(), 1000U) << "a chart is more than a header";
}

TEST_F(CliTest, PlotIntoAMissingDirectoryFailsAtRuntime) {
  const std::string path = "/nonexistent-dir/x.png";
  const RunResult result = run({"codes", "plot", "raskar", "-o", path});
  EXPECT_EQ(result.exit_code, 1) << result;
  EXPECT_TRUE(contains(result.err, path)) << result;
  EXPECT_FALSE(fs::exists(path));
}

TEST_F(CliTest, PlotWithABadCodeLeavesAnExistingFileIntact) {
  const fs::path png = dir_ / "keep.png";
  const std::string original = "not really a png, but it must survive\n";
  {
    std::ofstream stream(png, std::ios::binary);
    stream << original;
  }
  const RunResult result = run({"codes", "plot", "raskar", "1212x4", "-o", png.string()});
  EXPECT_EQ(result.exit_code, 2) << result;
  EXPECT_TRUE(contains(result.err, "1212x4")) << result;
  EXPECT_EQ(read_file(png), original);
  // No stray temporary files next to it either.
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("stdout-", 0) != 0 && name.rfind("stderr-", 0) != 0) names.push_back(name);
  }
  EXPECT_EQ(names, std::vector<std::string>{"keep.png"});
}

// ---------------------------------------------------------------------------
// codes list

TEST_F(CliTest, ListShowsTheLibrary) {
  const RunResult result = run({"codes", "list"});
  ASSERT_EQ(result.exit_code, 0) << result;
  EXPECT_TRUE(contains(result.out, "seed-maxmin-1")) << result;
  EXPECT_TRUE(contains(result.out, "raskar")) << result;
}

TEST_F(CliTest, ListJsonHasANameAndMeritsOnEveryLine) {
  const RunResult result = run({"codes", "list", "--json"});
  ASSERT_EQ(result.exit_code, 0) << result;
  const auto objects = json_lines(result.out);
  ASSERT_GE(objects.size(), 2U) << result;
  std::vector<std::string> names;
  for (const auto& object : objects) {
    ASSERT_TRUE(object.contains("name")) << object.dump();
    ASSERT_TRUE(object.contains("merits")) << object.dump();
    EXPECT_TRUE(object["merits"].is_object()) << object.dump();
    names.push_back(object["name"].get<std::string>());
  }
  EXPECT_NE(std::find(names.begin(), names.end(), "seed-maxmin-1"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "raskar"), names.end());
}

// ---------------------------------------------------------------------------
// --help

TEST_F(CliTest, HelpOnEverySubcommandSucceeds) {
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"--help"}, std::vector<std::string>{"codes", "--help"},
        std::vector<std::string>{"codes", "score", "--help"},
        std::vector<std::string>{"codes", "search", "--help"},
        std::vector<std::string>{"codes", "plot", "--help"},
        std::vector<std::string>{"codes", "list", "--help"}}) {
    std::string command;
    for (const auto& arg : args) command += " " + arg;
    SCOPED_TRACE("flutterscan" + command);
    const RunResult result = run(args);
    EXPECT_EQ(result.exit_code, 0) << result;
    EXPECT_TRUE(contains(result.out, "Usage")) << result;
  }
}

// ---------------------------------------------------------------------------
// simulate and deblur

constexpr const char* kCrosstalk = "0.90,0.08,0.01;0.10,0.85,0.12;0.01,0.07,0.88";

bool is_png(const fs::path& path) {
  return read_file(path).rfind("\x89PNG\r\n\x1a\n", 0) == 0;
}

class ImagingCliTest : public CliTest {
 protected:
  /// Simulates `scene` (the Code 128 label FS-0042 unless told) into dir_/frame.png
  /// (+ .json, .truth.png) at `electrons` per LED slot with noise seed `seed`.
  void simulate_label(const std::string& electrons = "3000", const std::string& seed = "3",
                      const std::string& scene = "code128:FS-0042") {
    const RunResult result = run({"simulate", "--scene", scene, "--code", "found-joint", "--blur",
                                  "52", "--electrons", electrons, "--crosstalk", kCrosstalk,
                                  "--seed", seed, "-o", (dir_ / "frame.png").string()});
    ASSERT_EQ(result.exit_code, 0) << result;
  }
  std::string frame() const { return (dir_ / "frame.png").string(); }
  std::string descriptor() const { return (dir_ / "frame.json").string(); }
  std::string output() const { return (dir_ / "sharp.png").string(); }
};

TEST_F(ImagingCliTest, SimulateWritesFrameDescriptorAndTruth) {
  simulate_label();
  EXPECT_TRUE(is_png(dir_ / "frame.png"));
  EXPECT_TRUE(is_png(dir_ / "frame.truth.png"));
  const json descriptor = json::parse(read_file(dir_ / "frame.json"));
  EXPECT_EQ(descriptor["format"], "flutterscan-capture");
  EXPECT_EQ(descriptor["version"], 1);
  EXPECT_EQ(descriptor["blur_px"], 52.0);
  EXPECT_EQ(descriptor["crosstalk"][1][2], 0.12);
}

TEST_F(ImagingCliTest, SimulateIsDeterministicForASeed) {
  simulate_label();
  const std::string first = read_file(dir_ / "frame.png");
  simulate_label();
  EXPECT_EQ(read_file(dir_ / "frame.png"), first);
}

TEST_F(ImagingCliTest, DeblurWithTheDescriptorDecodesTheLabel) {
  simulate_label();
  for (const char* method : {"joint-wiener", "tv"}) {
    const RunResult result = run({"deblur", frame(), "--descriptor", descriptor(), "--method",
                                  method, "--decode", "--json", "-o", output()});
    ASSERT_EQ(result.exit_code, 0) << result;
    const auto objects = json_lines(result.out);
    ASSERT_EQ(objects.size(), 1U);
    EXPECT_EQ(objects[0]["method"], method);
    EXPECT_TRUE(objects[0]["timings_ms"].contains("deblur"));
    ASSERT_TRUE(objects[0]["decoded"].is_array()) << result;
    EXPECT_EQ(objects[0]["decoded"].size(), 1U) << result;
    EXPECT_EQ(objects[0]["decoded"][0], "FS-0042") << result;
    // Each value with what backs it: a Code 128's own check, read on the first pass.
    ASSERT_EQ(objects[0]["codes"].size(), 1U) << result;
    EXPECT_EQ(objects[0]["codes"][0]["evidence"], "check") << result;
    EXPECT_EQ(objects[0]["codes"][0]["pass"], "first") << result;
    EXPECT_EQ(objects[0]["codes"][0]["decoder"], "zxing") << result;
    EXPECT_TRUE(objects[0]["unconfirmed"].empty()) << result;
    EXPECT_TRUE(is_png(output()));
  }
  // The cascade's tries by name; an unknown one is bad usage, named.
  const RunResult none = run({"deblur", frame(), "--descriptor", descriptor(), "--tries", "none",
                              "--decode", "--json", "-o", output()});
  ASSERT_EQ(none.exit_code, 0) << none;
  const RunResult unknown = run({"deblur", frame(), "--descriptor", descriptor(), "--tries",
                                 "bar-sums,guess", "--decode", "-o", output()});
  EXPECT_EQ(unknown.exit_code, 2) << unknown;
  EXPECT_NE(unknown.err.find("'guess' is not a second-pass try"), std::string::npos) << unknown;
}

TEST_F(ImagingCliTest, DeblurScoresAgainstTheTruth) {
  simulate_label();
  const std::string truth = (dir_ / "frame.truth.png").string();
  double psnr[2] = {0, 0};
  int i = 0;
  for (const char* method : {"joint-wiener", "tv"}) {
    const RunResult result = run({"deblur", frame(), "--descriptor", descriptor(), "--method",
                                  method, "--truth", truth, "--json", "-o", output()});
    ASSERT_EQ(result.exit_code, 0) << result;
    const auto objects = json_lines(result.out);
    ASSERT_EQ(objects.size(), 1U);
    psnr[i] = objects[0]["truth"]["psnr_db"].get<double>();
    EXPECT_GT(objects[0]["truth"]["ssim"].get<double>(), 0.3) << result;
    ++i;
  }
  EXPECT_GT(psnr[0], 20.0);
  EXPECT_GT(psnr[1], psnr[0] + 5.0);  // tv's margin over joint Wiener on labels
  // The truth must match the input's size.
  const RunResult wrong =
      run({"deblur", frame(), "--descriptor", descriptor(), "--truth", frame(), "-o", output()});
  EXPECT_EQ(wrong.exit_code, 2) << wrong;
  EXPECT_NE(wrong.err.find("--truth"), std::string::npos) << wrong;
}

TEST_F(ImagingCliTest, DeblurFromFlagsAlsoDecodes) {
  simulate_label();
  const json descriptor_json = json::parse(read_file(descriptor()));
  const RunResult result = run({"deblur", frame(), "--code", "found-joint", "--blur", "52",
                                "--crosstalk", kCrosstalk, "--black-level", "64", "--gain",
                                std::to_string(descriptor_json["gain_e_per_dn"].get<double>()),
                                "--decode", "-o", output()});
  ASSERT_EQ(result.exit_code, 0) << result;
  EXPECT_TRUE(contains(result.out, "decoded: FS-0042")) << result;
}

TEST_F(ImagingCliTest, AnOpaqueAlphaChannelIsDroppedAndATransparentPixelRefused) {
  // Some tools write RGBA whatever the picture: an alpha that hides nothing is
  // dropped (the same picture as the RGB frame's); one that hides a pixel is
  // refused, naming where.
  simulate_label();
  ASSERT_EQ(run({"deblur", frame(), "--descriptor", descriptor(), "--method", "joint-wiener", "-o",
                 output()})
                .exit_code,
            0);
  const cv::Mat rgb = cv::imread(frame(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(rgb.channels(), 3);
  cv::Mat rgba(rgb.size(), CV_MAKETYPE(rgb.depth(), 4));
  const cv::Mat alpha(rgb.size(), rgb.depth(), cv::Scalar(65535));
  const int pairs[] = {0, 0, 1, 1, 2, 2, 3, 3};
  const cv::Mat sources[] = {rgb, alpha};
  cv::mixChannels(sources, 2, &rgba, 1, pairs, 4);
  const std::string opaque = (dir_ / "opaque.png").string();
  ASSERT_TRUE(cv::imwrite(opaque, rgba));
  const std::string opaque_output = (dir_ / "opaque-sharp.png").string();
  const RunResult read = run({"deblur", opaque, "--descriptor", descriptor(), "--method",
                              "joint-wiener", "-o", opaque_output});
  ASSERT_EQ(read.exit_code, 0) << read;
  EXPECT_EQ(read_file(opaque_output), read_file(output()));
  rgba.at<cv::Vec<std::uint16_t, 4>>(7, 12)[3] = 1000;
  const std::string holed = (dir_ / "holed.png").string();
  ASSERT_TRUE(cv::imwrite(holed, rgba));
  expect_usage_error({"deblur", holed, "--descriptor", descriptor(), "-o", output()},
                     {"holed.png", "transparent", "x 12, y 7"});
}

TEST_F(ImagingCliTest, DeblurRefusesBadInputNamingIt) {
  simulate_label();
  const std::string not_an_image = (dir_ / "notes.png").string();
  std::ofstream(not_an_image) << "hello";
  expect_usage_error(
      {"deblur", (dir_ / "missing.png").string(), "--descriptor", descriptor(), "-o", output()},
      {"missing.png", "does not exist"});
  expect_usage_error(
      {"deblur", not_an_image, "--code", "found-joint", "--blur", "52", "-o", output()},
      {"notes.png", "cannot read"});
  expect_usage_error({"deblur", frame(), "--code", "found-joint", "--blur", "900", "-o", output()},
                     {"not shorter than the image"});
  expect_usage_error(
      {"deblur", frame(), "--descriptor", descriptor(), "--code", "seed-maxmin-1", "-o", output()},
      {"disagrees with the descriptor"});
  expect_usage_error({"deblur", frame(), "--code", "found-joint", "--blur", "nan", "-o", output()},
                     {"blur"});
  expect_usage_error({"deblur", frame(), "--code", "found-joint", "--blur", "52", "--read-noise",
                      "-3", "-o", output()},
                     {"read noise"});
  expect_usage_error({"deblur", frame(), "--code", "found-joint", "--blur", "52", "--crosstalk",
                      "1,0,0;1,0,0;0,0,1", "-o", output()},
                     {"singular"});
  expect_usage_error({"deblur", frame(), "-o", output()}, {"--descriptor", "--code"});
  expect_usage_error(
      {"deblur", frame(), "--descriptor", descriptor(), "--method", "magic", "-o", output()},
      {"unknown method 'magic'"});
  expect_usage_error({"deblur", frame(), "--code", "raskar", "--blur", "52", "-o", output()},
                     {"grey frame"});
  expect_usage_error({"deblur", frame(), "--descriptor", descriptor(), "--pixel-model", "gaussian",
                      "-o", output()},
                     {"--pixel-model", "band-limited"});
  EXPECT_FALSE(fs::exists(output()));
}

TEST_F(ImagingCliTest, DeblurTakesThePixelModelItIsTold) {
  // The simulator's frames are box pixels: told band-limited, the deblur still runs and reads,
  // and its JSON says which model it used.
  simulate_label();
  for (const char* pixels : {"box-aperture", "band-limited"}) {
    const RunResult result = run({"deblur", frame(), "--descriptor", descriptor(), "--pixel-model",
                                  pixels, "--decode", "--json", "-o", output()});
    ASSERT_EQ(result.exit_code, 0) << result;
    const auto objects = json_lines(result.out);
    ASSERT_EQ(objects.size(), 1U);
    EXPECT_EQ(objects[0]["pixel_model"], pixels) << result;
    ASSERT_TRUE(objects[0]["decoded"].is_array()) << result;
    EXPECT_EQ(objects[0]["decoded"].size(), 1U) << pixels << ": " << result;
  }
}

TEST_F(ImagingCliTest, FailedDeblurLeavesAnExistingOutputAlone) {
  simulate_label();
  std::ofstream(output(), std::ios::binary) << "previous result";
  expect_usage_error(
      {"deblur", frame(), "--descriptor", descriptor(), "--method", "magic", "-o", output()},
      {"magic"});
  EXPECT_EQ(read_file(output()), "previous result");
}

TEST_F(ImagingCliTest, SimulateRefusesBadScenesAndCodes) {
  expect_usage_error({"simulate", "--scene", "poster:X", "--code", "found-joint", "-o", frame()},
                     {"poster"});
  expect_usage_error({"simulate", "--scene", "code128:X", "--code", "12x4", "-o", frame()},
                     {"slot 2"});
  expect_usage_error(
      {"simulate", "--scene", "code128:X", "--code", "found-joint", "--blur", "700", "-o", frame()},
      {"--blur"});
  EXPECT_FALSE(fs::exists(frame()));
}

TEST_F(ImagingCliTest, APhotoSceneIsPlacedOnTheBeltRecordedAndReadBack) {
  simulate_label();
  // The label's truth (a 640 x 360 grey PNG) serves as the photo.
  const std::string photo = (dir_ / "photo.png").string();
  fs::rename(dir_ / "frame.truth.png", photo);
  const RunResult result =
      run({"simulate", "--scene", "photo:" + photo, "--rotate", "3", "--code", "found-joint",
           "--blur", "52", "--electrons", "3000", "--crosstalk", kCrosstalk, "-o", frame()});
  ASSERT_EQ(result.exit_code, 0) << result;
  const json written = json::parse(read_file(descriptor()));
  const json& record = written["simulation"]["photo"];
  EXPECT_EQ(record["path"], photo);
  EXPECT_EQ(record["size"], json::array({640, 360}));
  EXPECT_EQ(record["rotate_deg"], 3.0);
  EXPECT_EQ(record["reflectance"].size(), 2u);
  EXPECT_TRUE(contains(record["bands"].get<std::string>(), "grey")) << record;
  // Sized to the photo turned by 3 degrees, the belt around it and the blur along x.
  const std::string bytes = read_file(frame());
  const auto be32 = [&](std::size_t at) {
    return (static_cast<unsigned char>(bytes[at]) << 24) |
           (static_cast<unsigned char>(bytes[at + 1]) << 16) |
           (static_cast<unsigned char>(bytes[at + 2]) << 8) |
           static_cast<unsigned char>(bytes[at + 3]);
  };
  EXPECT_EQ(be32(16), 658u + 16u + 104u);  // 640 cos 3 + 360 sin 3 = 657.96 -> 658
  EXPECT_EQ(be32(20), 394u + 16u);         // 640 sin 3 + 360 cos 3 = 393.002 -> 394
  const RunResult read = run({"deblur", frame(), "--descriptor", descriptor(), "--method", "tv",
                              "--decode", "--json", "-o", output()});
  ASSERT_EQ(read.exit_code, 0) << read;
  const auto objects = json_lines(read.out);
  ASSERT_EQ(objects.size(), 1U);
  EXPECT_EQ(objects[0]["decoded"], json::array({"FS-0042"})) << read;
}

TEST_F(ImagingCliTest, TheCascadeReadsADimLabelJointWienerMisses) {
  // 150 e-: joint Wiener's latent reads nothing; the cascade deblurs the label's
  // window again and reads it.
  ASSERT_NO_FATAL_FAILURE(simulate_label("150"));
  const std::string plain_output = (dir_ / "plain.png").string();
  const RunResult plain = run({"deblur", frame(), "--descriptor", descriptor(), "--method",
                               "joint-wiener", "--decode", "--json", "-o", plain_output});
  ASSERT_EQ(plain.exit_code, 0) << plain;
  EXPECT_TRUE(json_lines(plain.out)[0]["decoded"].empty()) << plain;
  const RunResult cascade = run({"deblur", frame(), "--descriptor", descriptor(), "--method",
                                 "cascade", "--decode", "--json", "-o", output()});
  ASSERT_EQ(cascade.exit_code, 0) << cascade;
  const json report = json_lines(cascade.out)[0];
  EXPECT_EQ(report["decoded"], json::array({"FS-0042"})) << cascade;
  ASSERT_EQ(report["second_pass"]["windows"].size(), 1u) << cascade;
  EXPECT_EQ(report["second_pass"]["windows"][0]["read"], json::array({"FS-0042"}));
  // The window's second latent is in the picture written (joint Wiener's elsewhere).
  EXPECT_NE(read_file(output()), read_file(plain_output));
  // A raw Bayer mosaic has no RGB frame for the windows: refused by name, nothing written.
  ASSERT_EQ(run({"simulate", "--scene", "code128:FS-0042", "--code", "found-joint", "--blur", "52",
                 "--bayer", "-o", (dir_ / "bayer.png").string()})
                .exit_code,
            0);
  const std::string bayer_output = (dir_ / "bayer-sharp.png").string();
  expect_usage_error({"deblur", (dir_ / "bayer.png").string(), "--descriptor",
                      (dir_ / "bayer.json").string(), "--method", "cascade", "-o", bayer_output},
                     {"cascade", "Bayer"});
  EXPECT_FALSE(fs::exists(bayer_output));
  // Without --method a mosaic gets the sharpest method it allows: tv.
  const RunResult bayer = run({"deblur", (dir_ / "bayer.png").string(), "--descriptor",
                               (dir_ / "bayer.json").string(), "--json", "-o", bayer_output});
  ASSERT_EQ(bayer.exit_code, 0) << bayer;
  EXPECT_EQ(json_lines(bayer.out)[0]["method"], "tv") << bayer;
}

TEST_F(ImagingCliTest, TheCascadesPictureIsTvsOverALabelJointWienerReadsToo) {
  // 1000 e-: joint Wiener reads the label, through the noise of its inverse
  // filter. Offline the cascade deblurs the label's window again anyway: the
  // picture written shows tv's latent there and tv's on the whole frame
  // elsewhere (closer to the scene), and the code is reported once.
  ASSERT_NO_FATAL_FAILURE(simulate_label("1000", "5"));
  const std::string truth = (dir_ / "frame.truth.png").string();
  const std::string plain_output = (dir_ / "plain.png").string();
  const RunResult plain =
      run({"deblur", frame(), "--descriptor", descriptor(), "--method", "joint-wiener", "--decode",
           "--truth", truth, "--json", "-o", plain_output});
  ASSERT_EQ(plain.exit_code, 0) << plain;
  const json plain_report = json_lines(plain.out)[0];
  ASSERT_EQ(plain_report["decoded"], json::array({"FS-0042"})) << plain;
  const RunResult cascade =
      run({"deblur", frame(), "--descriptor", descriptor(), "--method", "cascade", "--decode",
           "--truth", truth, "--json", "-o", output()});
  ASSERT_EQ(cascade.exit_code, 0) << cascade;
  const json report = json_lines(cascade.out)[0];
  EXPECT_EQ(report["decoded"], json::array({"FS-0042"})) << cascade;
  ASSERT_GE(report["second_pass"]["windows"].size(), 1u) << cascade;
  EXPECT_GT(report["truth"]["psnr_db"].get<double>(),
            plain_report["truth"]["psnr_db"].get<double>() + 1.5)
      << plain << cascade;
  // Beyond the windows the picture is tv's on the whole frame: within 4 dB of
  // tv's own (the windows' tv reads with a lighter prior: 36.2 against 39.1 dB;
  // joint Wiener's belt left it at 28.3).
  const RunResult tv = run({"deblur", frame(), "--descriptor", descriptor(), "--method", "tv",
                            "--truth", truth, "--json", "-o", (dir_ / "tv.png").string()});
  ASSERT_EQ(tv.exit_code, 0) << tv;
  EXPECT_GT(report["truth"]["psnr_db"].get<double>(),
            json_lines(tv.out)[0]["truth"]["psnr_db"].get<double>() - 4.0)
      << tv << cascade;
  // Offline, the cascade is what deblur does unless told otherwise: the same picture.
  const std::string default_output = (dir_ / "default.png").string();
  const RunResult by_default =
      run({"deblur", frame(), "--descriptor", descriptor(), "--json", "-o", default_output});
  ASSERT_EQ(by_default.exit_code, 0) << by_default;
  EXPECT_EQ(json_lines(by_default.out)[0]["method"], "cascade") << by_default;
  EXPECT_EQ(read_file(default_output), read_file(output()));
}

TEST_F(ImagingCliTest, TheCascadesPictureIsTvsWholeFrameBeyondItsWindowsWhenTheBeltMovesUp) {
  // Motion along -y: the windows are in camera coordinates, tv's latent beyond
  // them is made in the motion frame. Outside every window the cascade's
  // picture is tv's, pixel for pixel; inside, the second pass's.
  ASSERT_EQ(run({"simulate",
                 "--scene",
                 "code128:FS-0042",
                 "--code",
                 "found-joint",
                 "--blur",
                 "52",
                 "--direction=-y",
                 "--electrons",
                 "1000",
                 "--crosstalk",
                 kCrosstalk,
                 "--seed",
                 "5",
                 "--width",
                 "420",
                 "--height",
                 "700",
                 "-o",
                 frame()})
                .exit_code,
            0);
  const std::string tv_output = (dir_ / "tv.png").string();
  ASSERT_EQ(
      run({"deblur", frame(), "--descriptor", descriptor(), "--method", "tv", "-o", tv_output})
          .exit_code,
      0);
  const RunResult cascade =
      run({"deblur", frame(), "--descriptor", descriptor(), "--decode", "--json", "-o", output()});
  ASSERT_EQ(cascade.exit_code, 0) << cascade;
  const json report = json_lines(cascade.out)[0];
  EXPECT_EQ(report["decoded"], json::array({"FS-0042"})) << cascade;
  const json& windows = report["second_pass"]["windows"];
  ASSERT_GE(windows.size(), 1u) << cascade;
  const cv::Mat tv = cv::imread(tv_output, cv::IMREAD_UNCHANGED);
  const cv::Mat picture = cv::imread(output(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(tv.size(), picture.size());
  int outside_differ = 0, inside_differ = 0;
  for (int y = 0; y < picture.rows; ++y)
    for (int x = 0; x < picture.cols; ++x) {
      const bool inside = std::any_of(windows.begin(), windows.end(), [&](const json& w) {
        return x >= w["x"].get<int>() && x < w["x"].get<int>() + w["width"].get<int>() &&
               y >= w["y"].get<int>() && y < w["y"].get<int>() + w["height"].get<int>();
      });
      const bool differ = tv.at<std::uint16_t>(y, x) != picture.at<std::uint16_t>(y, x);
      (inside ? inside_differ : outside_differ) += differ;
    }
  EXPECT_EQ(outside_differ, 0) << cascade;
  EXPECT_GT(inside_differ, 0) << cascade;
}

TEST_F(ImagingCliTest, TheBarSumsFindTheSlopeOfARealLabelTurnedEightDegrees) {
  // ean13-2-05 of the shared real-label photos (../shared/data beside the
  // repository, from ZXing's test images; skipped where absent): an EAN-13 turned
  // 8 degrees beside a second code cut by the photo's edge, print and a shadow.
  // At 1000 e- tv's latent of its window reads no linear code, so its rows are
  // summed along the bars: along the slope found on the first pass's latent,
  // -0.14 px per row as on the sharp scene (on tv's latent it was 0.00).
  const char* folder = std::getenv("FLUTTERSCAN_REAL_LABELS");
  const fs::path photo =
      fs::path(folder != nullptr ? folder : REAL_LABELS_BESIDE_REPOSITORY) / "ean13-2-05.png";
  if (!fs::exists(photo)) GTEST_SKIP() << "no real-label photos at " << photo.parent_path();
  const RunResult simulated =
      run({"simulate", "--scene", "photo:" + photo.string(), "--code", "seed-maxmin-1",
           "--electrons", "1000", "--seed", "7", "-o", frame()});
  ASSERT_EQ(simulated.exit_code, 0) << simulated;
  const RunResult result =
      run({"deblur", frame(), "--descriptor", descriptor(), "--decode", "--json", "-o", output()});
  ASSERT_EQ(result.exit_code, 0) << result;
  const json report = json_lines(result.out)[0];
  int summed = 0;
  for (const json& window : report["second_pass"]["windows"]) {
    if (!window.contains("bar_sums")) continue;
    ++summed;
    EXPECT_NEAR(window["bar_sums"]["slope"].get<double>(), -0.14, 0.03) << result;
  }
  EXPECT_GT(summed, 0) << result;
}

TEST_F(ImagingCliTest, WhereSeventeenRowsSummedReadNothingFortyNineDo) {
  // 18 e-: the Code 128 label's tv latent reads nothing, nor do its rows summed
  // 17 at a time along the bars; summed 49 at a time (the bars are taller)
  // they carry 49 times the light and read.
  ASSERT_NO_FATAL_FAILURE(simulate_label("18", "3"));
  const RunResult result =
      run({"deblur", frame(), "--descriptor", descriptor(), "--decode", "--json", "-o", output()});
  ASSERT_EQ(result.exit_code, 0) << result;
  const json report = json_lines(result.out)[0];
  EXPECT_EQ(report["decoded"], json::array({"FS-0042"})) << result;
  int read_on_sums = 0;
  for (const json& window : report["second_pass"]["windows"]) {
    if (window["read"].empty()) continue;
    ++read_on_sums;
    EXPECT_EQ(window["bar_sums"]["rows"], json::array({17, 49})) << result;
    EXPECT_EQ(window["bar_sums"]["read"], json::array({"FS-0042"})) << result;
  }
  EXPECT_EQ(read_on_sums, 1) << result;
}

TEST_F(ImagingCliTest, InDimLightTheCascadeReadsAMatrixCodeWithAnIsotropicPrior) {
  // tv's prior, heavier across the motion (bars upright), reads nothing in the
  // QR code's window, nor do the bar sums; the window deblurred again with the
  // same weight both ways reads it (tried only where nothing read): at 130 e-
  // at the reading weight (kappa 0.3); at 80 e- that flattens the 3 px modules
  // too, and half the weight reads.
  const std::vector<std::pair<std::string, json>> cases = {{"130", json::array({0.3})},
                                                           {"80", json::array({0.3, 0.15})}};
  for (const auto& [electrons, weights] : cases) {
    SCOPED_TRACE(electrons + " e-");
    ASSERT_NO_FATAL_FAILURE(simulate_label(electrons, "3", "qr:FS-QR-0042"));
    const RunResult result = run(
        {"deblur", frame(), "--descriptor", descriptor(), "--decode", "--json", "-o", output()});
    ASSERT_EQ(result.exit_code, 0) << result;
    const json report = json_lines(result.out)[0];
    EXPECT_EQ(report["decoded"], json::array({"FS-QR-0042"})) << result;
    ASSERT_EQ(report["second_pass"]["windows"].size(), 1u) << result;
    const json& window = report["second_pass"]["windows"][0];
    EXPECT_TRUE(window["bar_sums"]["read"].empty()) << result;
    EXPECT_EQ(window["isotropic"]["weights"], weights) << result;
    EXPECT_EQ(window["isotropic"]["read"], json::array({"FS-QR-0042"})) << result;
  }
}

TEST_F(ImagingCliTest, SimulateRefusesABadPhotoOrTurn) {
  simulate_label();
  const std::string photo = (dir_ / "frame.truth.png").string();
  expect_usage_error({"simulate", "--scene", "photo:" + (dir_ / "absent.png").string(), "--code",
                      "found-joint", "-o", output()},
                     {"absent.png"});
  expect_usage_error(
      {"simulate", "--scene", "photo:" + descriptor(), "--code", "found-joint", "-o", output()},
      {"frame.json"});
  expect_usage_error({"simulate", "--scene", "photo:" + photo, "--rotate", "nan", "--code",
                      "found-joint", "-o", output()},
                     {"--rotate"});
  expect_usage_error({"simulate", "--scene", "photo:" + photo, "--rotate", "720", "--code",
                      "found-joint", "-o", output()},
                     {"--rotate"});
  expect_usage_error({"simulate", "--scene", "code128:X", "--rotate", "10", "--code", "found-joint",
                      "-o", output()},
                     {"--rotate", "photo"});
  expect_usage_error({"simulate", "--scene", "photo:" + photo, "--width", "500", "--code",
                      "found-joint", "-o", output()},
                     {"needs a frame of at least 656 x 376"});
  EXPECT_FALSE(fs::exists(output()));
}

TEST_F(ImagingCliTest, BenchSpeedHasHelp) {
  const RunResult result = run({"bench", "speed", "--help"});
  EXPECT_EQ(result.exit_code, 0) << result;
  EXPECT_TRUE(contains(result.out, "--json")) << result;
}

// -- flutterscan calibrate ----------------------------------------------------

class CalibrateCliTest : public CliTest {
 protected:
  /// Simulates a 200x120 frame of `scene` under `code` into dir_/NAME.png (+ .json).
  std::string simulate(const std::string& name, const std::string& scene, const std::string& code,
                       const std::string& electrons, const std::string& blur, int seed,
                       const std::string& width = "200") {
    const std::string path = (dir_ / (name + ".png")).string();
    const RunResult result = run({"simulate",
                                  "--scene",
                                  scene,
                                  "--code",
                                  code,
                                  "--leds",
                                  "3",
                                  "--electrons",
                                  electrons,
                                  "--blur",
                                  blur,
                                  "--crosstalk",
                                  kCrosstalk,
                                  "--width",
                                  width,
                                  "--height",
                                  "120",
                                  "--seed",
                                  std::to_string(seed),
                                  "-o",
                                  path});
    EXPECT_EQ(result.exit_code, 0) << result;
    return path;
  }
  std::string config() const { return (dir_ / "line3.toml").string(); }
  void write_config() const {
    std::ofstream(config()) << "# line 3\n[optics]\npx_per_count = 0.5 # from the drawing\n";
  }
};

TEST_F(CalibrateCliTest, CrosstalkRecoversTheMatrixAndWritesTheConfig) {
  const std::string dark = simulate("dark", "flat:0.9", std::string(52, '7'), "0", "1", 1);
  std::vector<std::string> leds;
  for (char digit : {'1', '2', '4'})
    leds.push_back(simulate(std::string("led") + digit, "flat:0.9", std::string(52, digit), "3000",
                            "1", digit));
  write_config();
  const RunResult result = run({"calibrate", "crosstalk", "--dark", dark, "--led", leds[0], leds[1],
                                leds[2], "--config", config(), "--json"});
  ASSERT_EQ(result.exit_code, 0) << result;
  const json report = json::parse(result.out.substr(0, result.out.find('\n')));
  const double truth[3][3] = {{0.90, 0.08, 0.01}, {0.10, 0.85, 0.12}, {0.01, 0.07, 0.88}};
  for (int k = 0; k < 3; ++k) {
    const double column = truth[0][k] + truth[1][k] + truth[2][k];
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(report["crosstalk"][c][k].get<double>(), truth[c][k] / column, 0.01)
          << c << "," << k;
  }
  EXPECT_LT(report["condition_number"].get<double>(), 2.0);
  const std::string written = read_file(config());
  EXPECT_TRUE(contains(written, "# line 3")) << written;
  EXPECT_TRUE(contains(written, "px_per_count = 0.5 # from the drawing")) << written;
  EXPECT_TRUE(contains(written, "crosstalk = [[0.89")) << written;
  EXPECT_TRUE(contains(written, "black_level_dn = 64")) << written;
  // Bad input: frames of different sizes, a missing file.
  const std::string small = (dir_ / "small.png").string();
  ASSERT_EQ(run({"simulate", "--scene", "flat:0.9", "--code", std::string(52, '1'), "--leds", "3",
                 "--width", "100", "--height", "60", "-o", small})
                .exit_code,
            0);
  expect_usage_error({"calibrate", "crosstalk", "--dark", dark, "--led", small},
                     {"LED 0", "dark frame"});
  expect_usage_error({"calibrate", "crosstalk", "--dark", dark, "--led", "missing.png"},
                     {"missing.png"});
}

TEST_F(CalibrateCliTest, FlatWritesAFlatFieldThatDeblurUses) {
  const std::string dark = simulate("dark", "flat:0.9", std::string(52, '7'), "0", "1", 1);
  std::vector<std::string> leds;
  for (char digit : {'1', '2', '4'})
    leds.push_back(simulate(std::string("led") + digit, "flat:0.9", std::string(52, digit), "3000",
                            "1", digit));
  const std::string flat = (dir_ / "flat.json").string();
  const RunResult result = run({"calibrate", "flat", "--dark", dark, "--led", leds[0], leds[1],
                                leds[2], "--grid", "4x3", "-o", flat, "--json"});
  ASSERT_EQ(result.exit_code, 0) << result;
  const json file = json::parse(read_file(flat));
  EXPECT_EQ(file["format"], "flutterscan-flat-field");
  EXPECT_EQ(file["tiles"][0], 4);
  EXPECT_LT(file["largest_deviation"].get<double>(), 0.02);  // the simulator's light is uniform
  // A frame of the calibrated size deblurs with it; another size is refused by name.
  const std::string frame = simulate("frame", "flat:0.5", "found-mse", "3000", "20", 2);
  EXPECT_EQ(run({"deblur", frame, "--descriptor", (dir_ / "frame.json").string(), "--flat", flat,
                 "-o", (dir_ / "sharp.png").string()})
                .exit_code,
            0);
  const std::string big = (dir_ / "big.png").string();
  ASSERT_EQ(run({"simulate", "--scene", "flat:0.5", "--code", "found-mse", "--width", "300",
                 "--height", "120", "-o", big})
                .exit_code,
            0);
  expect_usage_error({"deblur", big, "--descriptor", (dir_ / "big.json").string(), "--flat", flat,
                      "-o", (dir_ / "sharp.png").string()},
                     {"flat field", "200x120"});
  expect_usage_error({"calibrate", "flat", "--dark", dark, "--led", leds[0], leds[1], leds[2],
                      "--grid", "4by3", "-o", flat},
                     {"--grid"});
}

TEST_F(CalibrateCliTest, NoiseRecoversGainAndReadNoise) {
  std::vector<std::string> args = {"calibrate",
                                   "noise",
                                   "--json",
                                   "--dark",
                                   simulate("d0", "flat:1", "rect-white", "0", "1", 11),
                                   simulate("d1", "flat:1", "rect-white", "0", "1", 12)};
  int seed = 20;
  for (const char* level : {"500", "2000", "5000", "8000"}) {
    args.emplace_back("--flat");
    for (int i = 0; i < 2; ++i)
      args.push_back(simulate(std::string("f") + level + std::to_string(i), "flat:1", "rect-white",
                              level, "1", ++seed));
  }
  const RunResult result = run(args);
  ASSERT_EQ(result.exit_code, 0) << result;
  const json report = json::parse(result.out.substr(0, result.out.find('\n')));
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(report["gain_e_per_dn"][c].get<double>(), 12000.0 / 4095.0, 0.03 * 2.93) << c;
    EXPECT_NEAR(report["read_noise_e"][c].get<double>(), 4.0, 0.4) << c;
  }
  expect_usage_error({"calibrate", "noise", "--dark", args[4], args[5], "--flat", args[7], args[8]},
                     {"two or more --flat pairs"});
}

TEST_F(CalibrateCliTest, SpeedGivesPixelsPerEncoderCount) {
  const std::string slow = simulate("slow", "code128:S1", "found-mse", "3000", "40", 3, "420");
  const std::string fast = simulate("fast", "code128:S2", "found-mse", "3000", "52.5", 4, "420");
  write_config();
  const RunResult result =
      run({"calibrate", "speed", slow, fast, "--encoder-counts", "80", "105", "--min-blur", "20",
           "--max-blur", "80", "--config", config(), "--json"});
  ASSERT_EQ(result.exit_code, 0) << result;
  const json report = json::parse(result.out.substr(0, result.out.find('\n')));
  EXPECT_NEAR(report["frames"][0]["blur_px"].get<double>(), 40.0, 0.25);
  EXPECT_NEAR(report["frames"][1]["blur_px"].get<double>(), 52.5, 0.25);
  EXPECT_NEAR(report["px_per_count"].get<double>(), 0.5, 0.005);
  // The config carries the measured value (written to 6 significant digits).
  const std::string written = read_file(config());
  const auto key = written.find("px_per_count = ");
  ASSERT_NE(key, std::string::npos) << written;
  EXPECT_NEAR(std::stod(written.substr(key + 15)), 0.5, 0.001) << written;
  EXPECT_NEAR(std::stod(written.substr(key + 15)), report["px_per_count"].get<double>(), 1e-5);
  EXPECT_FALSE(contains(read_file(config()), "from the drawing"));
  expect_usage_error({"calibrate", "speed", slow, fast, "--encoder-counts", "80"},
                     {"one count per frame"});
  fs::remove(dir_ / "slow.json");
  expect_usage_error({"calibrate", "speed", slow}, {"slow.png", "descriptor"});
}

// -- flutterscan calibrate, live: sim camera and sim controller --------------------

/// The live forms capture with the sim camera (a static white card, or labels on
/// the belt for speed) lit by the virtual controller, and must recover the
/// simulator's true values, set here away from the defaults.
class CalibrateLiveCliTest : public CalibrateCliTest {
 protected:
  /// `calibrate WHAT --camera sim --controller sim` with the sim options `options`.
  RunResult live(const std::string& what, const std::vector<std::string>& options,
                 const std::vector<std::string>& extra) {
    std::vector<std::string> args = {"calibrate", what, "--camera", "sim", "--controller", "sim"};
    for (const auto& option : options) {
      args.emplace_back("--camera-option");
      args.push_back(option);
    }
    args.insert(args.end(), extra.begin(), extra.end());
    return run(args);
  }
};

// True crosstalk (rows: channels, columns: LEDs) and black level of the sim below.
// Columns sum to 1.0, 0.95 and 0.92: the calibration must normalise them.
constexpr double kLiveCrosstalk[3][3] = {
    {0.80, 0.15, 0.02}, {0.15, 0.70, 0.10}, {0.05, 0.10, 0.80}};

TEST_F(CalibrateLiveCliTest, CrosstalkRecoversTheSimulatorsMatrixAndBlackLevel) {
  write_config();
  const RunResult result = live("crosstalk",
                                {"target=white:0.9", "width=256", "height=192", "black_level=80",
                                 "crosstalk=0.80,0.15,0.02,0.15,0.70,0.10,0.05,0.10,0.80"},
                                {"--frames", "4", "--config", config(), "--json"});
  ASSERT_EQ(result.exit_code, 0) << result;
  const json report = json::parse(result.out.substr(0, result.out.find('\n')));
  for (int k = 0; k < 3; ++k) {
    const double column = kLiveCrosstalk[0][k] + kLiveCrosstalk[1][k] + kLiveCrosstalk[2][k];
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(report["crosstalk"][c][k].get<double>(), kLiveCrosstalk[c][k] / column, 0.003)
          << c << "," << k;
    // Each LED gives a white card E x R x its column sum (12-bit, full well 12000 e-).
    EXPECT_NEAR(report["led_strength_dn"][k].get<double>(), 3000 * 0.9 * column * 4095 / 12000,
                0.01 * 3000 * 0.9 * column * 4095 / 12000)
        << k;
  }
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(report["black_level_dn"][c].get<double>(), 80, 0.5) << c;
  const std::string written = read_file(config());
  EXPECT_TRUE(contains(written, "px_per_count = 0.5 # from the drawing")) << written;
  EXPECT_TRUE(contains(written, "crosstalk = [[0.8")) << written;
  EXPECT_TRUE(contains(written, "black_level_dn = 80")) << written;
  // What it did to the controller is said on stderr.
  EXPECT_TRUE(contains(result.err, "disarmed")) << result;
  EXPECT_TRUE(contains(result.err, "LED 2")) << result;
}

TEST_F(CalibrateLiveCliTest, FlatMeasuresTheLightFallingOffTowardTheCorners) {
  const std::string flat = (dir_ / "flat.json").string();
  // No target given: the sim shows its white card for a white-target calibration.
  const RunResult result = live("flat", {"width=240", "height=180", "falloff=0.3"},
                                {"--grid", "4x3", "-o", flat, "--config", config(), "--json"});
  ASSERT_EQ(result.exit_code, 0) << result;
  EXPECT_TRUE(contains(result.err, "target=white")) << result;
  const json file = json::parse(read_file(flat));
  ASSERT_EQ(file["tiles"][0], 4);
  ASSERT_EQ(file["tiles"][1], 3);
  // The sim's light 1 - 0.3 r^2 (r = 1 at a corner), by its median over each tile.
  auto light = [](int tx, int ty) {
    std::vector<double> values;
    for (int y = 60 * ty; y < 60 * (ty + 1); ++y)
      for (int x = 60 * tx; x < 60 * (tx + 1); ++x) {
        const double dx = x - 119.5, dy = y - 89.5;
        values.push_back(1 - 0.3 * (dx * dx + dy * dy) / (119.5 * 119.5 + 89.5 * 89.5));
      }
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    return values[values.size() / 2];
  };
  const auto& mixing = file["mixing_dn"];
  for (int k = 0; k < 3; ++k)
    for (int t = 0; t < 12; ++t) {
      // Relative to tile 5 (second row, second column), each LED's own channel.
      const double measured =
          mixing[t * 9 + k * 3 + k].get<double>() / mixing[5 * 9 + k * 3 + k].get<double>();
      EXPECT_NEAR(measured, light(t % 4, t / 4) / light(1, 1), 0.02)
          << "LED " << k << " tile " << t;
    }
  EXPECT_GT(file["largest_deviation"].get<double>(), 0.08);  // 10.5% here
  EXPECT_TRUE(contains(read_file(config()), "flat_field = ")) << read_file(config());
}

TEST_F(CalibrateLiveCliTest, NoiseRecoversGainReadNoiseAndBlackLevel) {
  write_config();
  const RunResult result = live("noise",
                                {"target=white:1", "width=256", "height=192", "electrons=8000",
                                 "full_well=15000", "read_noise=6", "black_level=100"},
                                {"--config", config(), "--json"});
  ASSERT_EQ(result.exit_code, 0) << result;
  const json report = json::parse(result.out.substr(0, result.out.find('\n')));
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(report["gain_e_per_dn"][c].get<double>(), 15000.0 / 4095.0, 0.03 * 15000.0 / 4095.0)
        << c;
    EXPECT_NEAR(report["read_noise_e"][c].get<double>(), 6.0, 0.4) << c;
    EXPECT_NEAR(report["black_level_dn"][c].get<double>(), 100, 0.5) << c;
    // Four light levels (2, 4, 8 and 16 of 52 slots) and all of them in the fit range.
    EXPECT_EQ(report["points"][c].size(), 4u) << c;
  }
  const std::string written = read_file(config());
  EXPECT_TRUE(contains(written, "gain_e_per_dn = 3.6")) << written;
  EXPECT_TRUE(contains(written, "read_noise_e = ")) << written;
  EXPECT_TRUE(contains(result.err, "light level 16 of 52 slots")) << result;
}

TEST_F(CalibrateLiveCliTest, SpeedRecoversTheBlurAndPixelsPerEncoderCount) {
  write_config();
  // 10000 px/s over 52 slots of 100 us: 52 px of blur; 4 counts per px: 0.25 px per count.
  const RunResult result = live(
      "speed", {"width=640", "height=200", "counts_per_px=4"},
      {"--frames", "6", "--min-blur", "20", "--max-blur", "100", "--config", config(), "--json"});
  ASSERT_EQ(result.exit_code, 0) << result;
  const json report = json::parse(result.out.substr(0, result.out.find('\n')));
  EXPECT_NEAR(report["blur_px"].get<double>(), 52.0, 0.25);
  EXPECT_NEAR(report["px_per_count"].get<double>(), 0.25, 0.0025);
  EXPECT_GE(report["frames"].size(), 3u);
  for (const auto& frame : report["frames"])
    EXPECT_NEAR(frame["encoder_counts"].get<double>(), 208, 1) << frame;
  const std::string written = read_file(config());
  EXPECT_TRUE(contains(written, "px_per_count = 0.25")) << written;
  EXPECT_FALSE(contains(written, "from the drawing")) << written;
}

TEST_F(CalibrateLiveCliTest, ALineThatFailsExitsOneNamingCameraControllerAndStep) {
  // The camera ends after 3 frames: the dark frames (1 dropped + 4) never complete.
  const RunResult result = live(
      "crosstalk", {"target=white", "width=128", "height=96", "max_frames=3"}, {"--frames", "4"});
  EXPECT_EQ(result.exit_code, 1) << result;
  for (const char* needle : {"camera sim", "virtual controller", "dark frames", "ended after 3"})
    EXPECT_TRUE(contains(result.err, needle)) << "stderr lacks \"" << needle << "\"\n" << result;
}

TEST_F(CalibrateLiveCliTest, BadUsageIsRefusedNamingTheProblem) {
  const std::string dark = simulate("dark", "flat:0.9", std::string(52, '7'), "0", "1", 1);
  expect_usage_error({"calibrate", "crosstalk", "--dark", dark, "--camera", "sim"},
                     {"--dark and --led", "--camera", "not both"});
  expect_usage_error({"calibrate", "crosstalk", "--controller", "sim"},
                     {"--controller", "--camera"});
  expect_usage_error({"calibrate", "crosstalk"}, {"--dark and --led", "--camera"});
  expect_usage_error({"calibrate", "noise", "--camera", "sim", "--dark", dark, dark},
                     {"--dark and --flat", "not both"});
  expect_usage_error({"calibrate", "speed", "--camera", "sim", "--encoder-counts", "100"},
                     {"--encoder-counts", "exposure events"});
  expect_usage_error({"calibrate", "crosstalk", "--camera", "nosuch:cam", "--controller", "sim"},
                     {"nosuch"});
  expect_usage_error({"calibrate", "crosstalk", "--camera", "sim", "--controller", "sim",
                      "--camera-option", "target=grey"},
                     {"camera sim", "target", "grey"});
  expect_usage_error({"calibrate", "crosstalk", "--camera", "sim", "--controller", "sim",
                      "--camera-option", "target"},
                     {"--camera-option", "KEY=VALUE"});
  expect_usage_error({"calibrate", "noise", "--camera", "sim", "--lit-slots", "1", "4"},
                     {"--lit-slots"});
}

}  // namespace
