// GoogleTest main for tests that need umockdev's preload library: the binary
// re-executes itself under `umockdev-wrapper` (umockdev_reexec.hpp), so it runs
// the same from CTest, gtest_discover_tests and a shell. Exits 77 (skip) when
// umockdev-wrapper is not installed.

#include <gtest/gtest.h>

#include "umockdev_reexec.hpp"

int main(int argc, char** argv) {
  if (!flutterscan::capture::testing::run_under_umockdev(argc, argv)) return 77;
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
