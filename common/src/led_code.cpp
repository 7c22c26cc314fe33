#include "flutterscan/common/led_code.hpp"

namespace flutterscan {
namespace {

constexpr char kDigits[] = "0123456789abcdef";

int digit_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

int popcount(unsigned v) {
  int n = 0;
  for (; v != 0; v &= v - 1) ++n;
  return n;
}

CodeIssue issue_at(CodeError error, int slot, char character, int leds) {
  CodeIssue issue;
  issue.error = error;
  issue.slot = slot;
  issue.character = character;
  issue.leds = leds;
  return issue;
}

/// Appends to a fixed buffer, always leaving room for the terminator.
class TextSink {
 public:
  explicit TextSink(std::span<char> out) : out_(out) {}
  TextSink& text(std::string_view s) {
    for (char c : s) put(c);
    return *this;
  }
  TextSink& number(int v) {
    if (v < 0) {
      put('-');
      v = -v;
    }
    char digits[12];
    int n = 0;
    do {
      digits[n++] = static_cast<char>('0' + v % 10);
      v /= 10;
    } while (v != 0);
    while (n > 0) put(digits[--n]);
    return *this;
  }
  TextSink& character(char c) {
    put(c);
    return *this;
  }
  std::size_t finish() {
    if (!out_.empty()) out_[used_] = '\0';
    return used_;
  }

 private:
  void put(char c) {
    if (used_ + 1 < out_.size()) out_[used_++] = c;
  }
  std::span<char> out_;
  std::size_t used_ = 0;
};

std::string_view led_count_word(int n) {
  switch (n) {
    case 0:
      return "no LED";
    case 2:
      return "two LEDs";
    case 3:
      return "three LEDs";
    default:
      return "four LEDs";
  }
}

}  // namespace

Result<LedCode, CodeIssue> LedCode::parse(std::string_view digits, int leds, CodeRule rule) {
  std::array<std::uint8_t, kMaxSlots> masks{};
  if (digits.size() > static_cast<std::size_t>(kMaxSlots)) {
    CodeIssue issue = issue_at(CodeError::kTooLong, -1, 0, leds);
    issue.count = static_cast<int>(digits.size());
    return Result<LedCode, CodeIssue>::failure(issue);
  }
  for (std::size_t i = 0; i < digits.size(); ++i) {
    const int value = digit_value(digits[i]);
    if (value < 0)
      return Result<LedCode, CodeIssue>::failure(
          issue_at(CodeError::kNotADigit, static_cast<int>(i), digits[i], leds));
    masks[i] = static_cast<std::uint8_t>(value);
  }
  Result<LedCode, CodeIssue> result =
      from_masks(std::span<const std::uint8_t>(masks.data(), digits.size()), leds, rule);
  if (!result.ok()) {
    CodeIssue issue = result.error();
    if (issue.slot >= 0) issue.character = digits[static_cast<std::size_t>(issue.slot)];
    return Result<LedCode, CodeIssue>::failure(issue);
  }
  return result;
}

Result<LedCode, CodeIssue> LedCode::from_masks(std::span<const std::uint8_t> masks, int leds,
                                               CodeRule rule) {
  if (leds < 1 || leds > kMaxLeds) {
    CodeIssue issue = issue_at(CodeError::kBadLedCount, -1, 0, leds);
    issue.count = leds;
    return Result<LedCode, CodeIssue>::failure(issue);
  }
  if (masks.empty())
    return Result<LedCode, CodeIssue>::failure(issue_at(CodeError::kEmpty, -1, 0, leds));
  if (masks.size() > static_cast<std::size_t>(kMaxSlots)) {
    CodeIssue issue = issue_at(CodeError::kTooLong, -1, 0, leds);
    issue.count = static_cast<int>(masks.size());
    return Result<LedCode, CodeIssue>::failure(issue);
  }
  LedCode code;
  code.leds_ = static_cast<std::uint8_t>(leds);
  code.length_ = static_cast<std::uint16_t>(masks.size());
  for (std::size_t i = 0; i < masks.size(); ++i) {
    if ((masks[i] & ~code.all_leds_mask()) != 0)
      return Result<LedCode, CodeIssue>::failure(
          issue_at(CodeError::kNoSuchLed, static_cast<int>(i), kDigits[masks[i] & 0xF], leds));
    code.masks_[i] = masks[i];
  }
  if (rule == CodeRule::kOneOfN) {
    const CodeIssue issue = code.check_one_of_n();
    if (issue.error != CodeError::kNone) return Result<LedCode, CodeIssue>::failure(issue);
  }
  return Result<LedCode, CodeIssue>::success(code);
}

CodeIssue LedCode::check_one_of_n() const {
  for (int i = 0; i < length_; ++i) {
    if (popcount(mask(i)) != 1)
      return issue_at(CodeError::kNotOneOfN, i, kDigits[mask(i) & 0xF], leds_);
  }
  return CodeIssue{};
}

int LedCode::on_slots(int led) const {
  int n = 0;
  for (int i = 0; i < length_; ++i) n += is_on(i, led) ? 1 : 0;
  return n;
}

float LedCode::duty_cycle(int led) const {
  return length_ == 0 ? 0.0f : static_cast<float>(on_slots(led)) / static_cast<float>(length_);
}

LedCode LedCode::complement() const {
  LedCode out = *this;
  for (int i = 0; i < length_; ++i)
    out.set_mask(i, static_cast<std::uint8_t>(~mask(i) & all_leds_mask()));
  return out;
}

std::size_t LedCode::format(std::span<char> out) const {
  if (out.size() < static_cast<std::size_t>(length_)) return 0;
  for (int i = 0; i < length_; ++i) out[static_cast<std::size_t>(i)] = kDigits[mask(i) & 0xF];
  return static_cast<std::size_t>(length_);
}

std::size_t describe(const CodeIssue& issue, std::span<char> out) {
  TextSink sink(out);
  if (issue.slot >= 0) sink.text("slot ").number(issue.slot).text(": ");
  switch (issue.error) {
    case CodeError::kNone:
      sink.text("no error");
      break;
    case CodeError::kBadLedCount:
      sink.text("a code has 1 to 4 LEDs, not ").number(issue.count);
      break;
    case CodeError::kEmpty:
      sink.text("the code is empty: it needs at least one slot");
      break;
    case CodeError::kTooLong:
      sink.text("the code has ").number(issue.count).text(" slots; at most 256 are allowed");
      break;
    case CodeError::kNotADigit:
      sink.text("'")
          .character(issue.character)
          .text("' is not a digit of the code notation (0-9, a-f)");
      break;
    case CodeError::kNoSuchLed: {
      const int value = digit_value(issue.character);
      int highest = 0;
      for (int bit = 0; bit < 4; ++bit)
        if ((value >> bit) & 1) highest = bit;
      sink.text("digit ")
          .character(issue.character)
          .text(" lights LED ")
          .number(highest)
          .text(", but the code has ")
          .number(issue.leds)
          .text(issue.leds == 1 ? " LED (LED 0)" : " LEDs (LED 0 to ");
      if (issue.leds > 1) sink.number(issue.leds - 1).text(")");
      break;
    }
    case CodeError::kNotOneOfN:
      sink.text("digit ")
          .character(issue.character)
          .text(" lights ")
          .text(led_count_word(popcount(static_cast<unsigned>(digit_value(issue.character)))))
          .text(" in a one-of-")
          .number(issue.leds)
          .text(" code");
      break;
  }
  return sink.finish();
}

}  // namespace flutterscan
