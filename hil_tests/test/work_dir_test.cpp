// The tests' work directories: fresh for each test, gone once it passes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "hil_run.hpp"

namespace flutterscan::hil::test {
namespace {

TEST(WorkDir, IsFreshAndRemovedWithEverythingInItWhenTheTestHasNotFailed) {
  std::filesystem::path kept;
  {
    const auto dir = make_work_dir("work_dir_check");
    kept = dir.path();
    ASSERT_TRUE(std::filesystem::is_directory(kept));
    EXPECT_TRUE(std::filesystem::is_empty(kept));
    std::filesystem::create_directories(kept / "nested");
    std::ofstream(kept / "nested" / "record.json") << "{}";
    const std::string& as_text = dir;
    EXPECT_EQ(as_text, kept.string());
  }
  EXPECT_FALSE(std::filesystem::exists(kept));
}

}  // namespace
}  // namespace flutterscan::hil::test
