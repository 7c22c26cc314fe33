#pragma once
// Survives a failed assert() inside a library call.
//
// Debian builds ZXing-C++ with assertions on, and a few of its detectors
// assert on shapes a noisy deblurred frame can present (ZXing 1.4's Micro QR
// sampler: `intersect` in RegressionLine.h, zxing-cpp issues 855 and 1154).
// An assertion there would abort a session that has run for hours over one
// frame. Within `run_catching_assertions`, a failed assertion in this thread
// returns control here instead, with its message; everywhere else assert()
// behaves as usual (message, abort).
//
// How: this file defines glibc's `__assert_fail`, which the executable then
// exports ahead of libc's, and jumps back to the guarded call with
// siglongjmp. Objects the library had built inside the call are not
// destroyed: their memory is lost (bounded by one decode per failure, and
// failures are counted where they happen). Use it only around calls into
// libraries that keep no locks or global state across the call.

#include <functional>
#include <string>

namespace flutterscan::reader {

/// \brief Runs `call`; returns "" when it completes, or the failed
/// assertion's text ("file:line: function: Assertion `...' failed") when an
/// assert() inside it failed.
std::string run_catching_assertions(const std::function<void()>& call);

}  // namespace flutterscan::reader
