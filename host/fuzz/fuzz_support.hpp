#pragma once
// Shared by the host's libFuzzer targets (host/fuzz/README.md): a reader that
// takes typed values off the fuzzer's bytes (zeros once they run out), and the
// oracle check that ends the run with a message when an invariant fails.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <span>
#include <string>
#include <vector>

namespace flutterscan::fuzz {

/// \brief Fails the input: prints what broke and aborts (libFuzzer keeps the input).
[[noreturn]] inline void oracle_failed(const char* what, const std::string& detail,
                                       const char* file, int line) {
  std::fprintf(stderr, "%s:%d: invariant violated: %s\n  %s\n", file, line, what, detail.c_str());
  std::fflush(stderr);
  std::abort();
}

#define FUZZ_CHECK(condition, detail)                                               \
  do {                                                                              \
    if (!(condition))                                                               \
      ::flutterscan::fuzz::oracle_failed(#condition, (detail), __FILE__, __LINE__); \
  } while (false)

/// \brief With FUZZ_TRACE=1 in the environment: one line per outcome (to check
/// that seeds get where they should).
inline bool tracing() {
  static const bool on = std::getenv("FUZZ_TRACE") != nullptr;
  return on;
}
inline void trace(const std::string& text) {
  if (tracing()) std::fprintf(stderr, "  %s\n", text.c_str());
}

/// \brief Typed values from the input, front to back; zeros after the end.
class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  std::size_t left() const { return size_ - used_; }
  bool empty() const { return left() == 0; }

  std::uint8_t u8() { return used_ < size_ ? data_[used_++] : 0; }
  std::uint16_t u16() { return static_cast<std::uint16_t>(u8() | u8() << 8); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(u16() | std::uint32_t{u16()} << 16); }
  std::uint64_t u64() { return u32() | std::uint64_t{u32()} << 32; }
  bool flag() { return (u8() & 1) != 0; }
  /// A value in [0, n) (n > 0).
  std::uint32_t below(std::uint32_t n) { return n == 0 ? 0 : u32() % n; }
  /// Any double, NaN and infinities included.
  double any_double() {
    const std::uint64_t bits = u64();
    double value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }
  /// Mostly ordinary numbers in [lo, hi], sometimes hostile ones (NaN, inf, huge, negative).
  double number(double lo, double hi) {
    const std::uint8_t kind = u8();
    if (kind < 200) return lo + (hi - lo) * (u16() / 65535.0);
    static constexpr double kHostile[] = {0.0, -1.0, 1e6, 1e9, 1e15, -1e15, 1e300, -0.0};
    if (kind < 248) return kHostile[kind % 8];
    return any_double();
  }
  /// `n` bytes (fewer at the end).
  std::vector<std::uint8_t> take(std::size_t n) {
    n = std::min(n, left());
    std::vector<std::uint8_t> out(data_ + used_, data_ + used_ + n);
    used_ += n;
    return out;
  }
  std::vector<std::uint8_t> rest() { return take(left()); }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t used_ = 0;
};

}  // namespace flutterscan::fuzz
