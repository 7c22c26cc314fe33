#pragma once
// Result<T, E>: a value or an error, for code that may not throw (common/ and
// firmware/). Freestanding: no heap, no exceptions.

#include <utility>

namespace flutterscan {

/// \brief A value of type T, or an error of type E explaining why there is none.
template <typename T, typename E>
class Result {
 public:
  /// \brief A successful result holding `value`.
  static constexpr Result success(T value) { return Result(std::move(value), E{}, true); }
  /// \brief A failed result holding `error`.
  static constexpr Result failure(E error) { return Result(T{}, std::move(error), false); }

  constexpr bool ok() const { return ok_; }
  constexpr explicit operator bool() const { return ok_; }
  /// \brief The value; meaningful only when ok().
  constexpr const T& value() const { return value_; }
  constexpr T& value() { return value_; }
  /// \brief The error; meaningful only when !ok().
  constexpr const E& error() const { return error_; }

 private:
  constexpr Result(T value, E error, bool ok)
      : value_(std::move(value)), error_(std::move(error)), ok_(ok) {}
  T value_;
  E error_;
  bool ok_;
};

}  // namespace flutterscan
