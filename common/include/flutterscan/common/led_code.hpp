#pragma once
// LED-pattern codes: for each time slot of an exposure, the bit mask of the
// LEDs that are on. Notation (docs/conventions.md): one hex digit per slot, digit i is
// slot i (slot 0 first in time), bit k of the digit is LED k (1 = red,
// 2 = green, 4 = blue). A single flutter-shutter code is a one-LED code, so
// its digit string is the plain bit string ("1010...").
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "flutterscan/common/result.hpp"

namespace flutterscan {

inline constexpr int kMaxLeds = 4;
inline constexpr int kMaxSlots = 256;

/// \brief What is wrong with a code string or a code.
enum class CodeError : std::uint8_t {
  kNone,
  kBadLedCount,  ///< the LED count is outside 1..kMaxLeds
  kEmpty,        ///< no slots
  kTooLong,      ///< more than kMaxSlots slots
  kNotADigit,    ///< a character that is not a hex digit
  kNoSuchLed,    ///< a digit lights an LED the code does not have
  kNotOneOfN,    ///< a slot lights no LED or several, where exactly one is required
};

/// \brief An error with where it happened: enough to say "slot 17: digit 3 ...".
struct CodeIssue {
  CodeError error = CodeError::kNone;
  int slot = -1;       ///< offending slot, -1 where the error is not at a slot
  char character = 0;  ///< offending character or digit as written
  int leds = 0;        ///< LED count of the code (for the message)
  int count = 0;       ///< kTooLong: slots given; kBadLedCount: LEDs asked for
};

/// \brief Whether a code must light exactly one LED per slot.
enum class CodeRule : std::uint8_t { kAnyMask, kOneOfN };

/// \brief An LED pattern of 1..4 LEDs and 1..256 slots.
class LedCode {
 public:
  constexpr LedCode() = default;

  /// \brief Parses the digit notation for a code of `leds` LEDs.
  static Result<LedCode, CodeIssue> parse(std::string_view digits, int leds,
                                          CodeRule rule = CodeRule::kAnyMask);

  /// \brief Builds a code from per-slot masks (same checks as parse).
  static Result<LedCode, CodeIssue> from_masks(std::span<const std::uint8_t> masks, int leds,
                                               CodeRule rule = CodeRule::kAnyMask);

  constexpr int leds() const { return leds_; }
  constexpr int length() const { return length_; }
  constexpr std::uint8_t mask(int slot) const { return masks_[static_cast<std::size_t>(slot)]; }
  constexpr bool is_on(int slot, int led) const { return (mask(slot) >> led) & 1U; }
  constexpr std::span<const std::uint8_t> masks() const {
    return {masks_.data(), static_cast<std::size_t>(length_)};
  }

  /// \brief Sets one slot's mask. The caller keeps the mask within leds().
  constexpr void set_mask(int slot, std::uint8_t mask) {
    masks_[static_cast<std::size_t>(slot)] = mask;
  }

  /// \brief The first slot that lights no LED or several; kNone if every slot lights one.
  CodeIssue check_one_of_n() const;
  bool is_one_of_n() const { return check_one_of_n().error == CodeError::kNone; }

  /// \brief Number of slots in which `led` is on.
  int on_slots(int led) const;
  /// \brief Fraction of the exposure in which `led` is on.
  float duty_cycle(int led) const;

  /// \brief Every LED's on and off swapped in every slot.
  LedCode complement() const;

  /// \brief Writes the digit notation into `out` (no terminator); returns the
  /// characters written, or 0 if `out` is shorter than length().
  std::size_t format(std::span<char> out) const;

  friend constexpr bool operator==(const LedCode& a, const LedCode& b) {
    if (a.leds_ != b.leds_ || a.length_ != b.length_) return false;
    for (int i = 0; i < a.length_; ++i)
      if (a.mask(i) != b.mask(i)) return false;
    return true;
  }

 private:
  constexpr std::uint8_t all_leds_mask() const {
    return static_cast<std::uint8_t>((1U << leds_) - 1U);
  }

  std::uint8_t leds_ = 1;
  std::uint16_t length_ = 0;
  std::array<std::uint8_t, kMaxSlots> masks_{};
};

/// \brief Writes a one-line English description of `issue` into `out`
/// (NUL-terminated, truncated to fit); returns the characters written.
/// Example: "slot 17: digit 3 lights two LEDs in a one-of-3 code".
std::size_t describe(const CodeIssue& issue, std::span<char> out);

}  // namespace flutterscan
