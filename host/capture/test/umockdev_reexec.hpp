#pragma once
// Running under umockdev's preload library: a program that needs it calls
// run_under_umockdev() first thing in main(); without the library in
// LD_PRELOAD the program re-executes itself under `umockdev-wrapper`.

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace flutterscan::capture::testing {

/// \brief Returns when the preload library is active; otherwise replaces the
/// process with `umockdev-wrapper argv...`. If that cannot start, prints why
/// and returns false: the caller exits 77 (skip).
inline bool run_under_umockdev(int argc, char** argv) {
  const char* preload = std::getenv("LD_PRELOAD");
  if (preload != nullptr && std::strstr(preload, "libumockdev-preload") != nullptr) return true;
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
  return false;
}

}  // namespace flutterscan::capture::testing
