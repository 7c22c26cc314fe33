// GoogleTest main for tests that need umockdev's preload library: without it
// in LD_PRELOAD, the binary re-executes itself under `umockdev-wrapper`, so it
// runs the same from CTest, gtest_discover_tests and a shell. Exits 77 (skip)
// when umockdev-wrapper is not installed.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  const char* preload = std::getenv("LD_PRELOAD");
  if (preload == nullptr || std::strstr(preload, "libumockdev-preload") == nullptr) {
    // The preload library comes before the sanitizer runtime in sanitizer
    // builds; ASan would refuse to start over that.
    std::string asan = std::getenv("ASAN_OPTIONS") ? std::getenv("ASAN_OPTIONS") : "";
    if (asan.find("verify_asan_link_order") == std::string::npos) {
      asan += std::string(asan.empty() ? "" : ":") + "verify_asan_link_order=0";
      ::setenv("ASAN_OPTIONS", asan.c_str(), 1);
    }
    std::vector<char*> args;
    args.push_back(const_cast<char*>("umockdev-wrapper"));
    for (int i = 0; i < argc; ++i) args.push_back(argv[i]);
    args.push_back(nullptr);
    ::execvp("umockdev-wrapper", args.data());
    std::fprintf(stderr, "%s: cannot run under umockdev-wrapper (%s); install umockdev. Skipped.\n",
                 argv[0], std::strerror(errno));
    return 77;
  }
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
