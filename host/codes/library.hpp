#pragma once
// The built-in code library: reference codes, the seed's codes and the best
// codes this project has found (docs/codes.md says how each was found).

#include <optional>
#include <span>
#include <string_view>

#include "flutterscan/common/led_code.hpp"

namespace flutterscan::codes {

struct LibraryCode {
  std::string_view name;
  std::string_view digits;
  int leds;
  std::string_view origin;  ///< one line: where the code comes from
  bool seed_triplet;        ///< one of the seed's optimised one-of-3 codes
};

/// \brief Every code of the library, reference codes first.
std::span<const LibraryCode> code_library();

/// \brief The library entry named `name`, if any.
std::optional<LibraryCode> find_library_code(std::string_view name);

/// \brief A library entry as a code.
LedCode to_code(const LibraryCode& entry);

}  // namespace flutterscan::codes
