#include "reader/ean_upc_layout.hpp"

namespace flutterscan::reader {

bool is_ean_upc(std::string_view format) {
  return format == "EAN-13" || format == "UPC-A" || format == "EAN-8" || format == "UPC-E";
}

std::optional<EanUpcLayout> ean_upc_layout(std::string_view format) {
  if (!is_ean_upc(format)) return std::nullopt;
  const bool upc_e = format == "UPC-E";
  const int per_side = format == "EAN-8" ? 4 : 6;
  EanUpcLayout l;
  l.left_characters = per_side;
  l.both_parities = format != "EAN-8";
  int at = 0;
  // A guard of `n` modules from `at`, alternating from a bar or a space.
  auto guard = [&](int n, bool bar_first) {
    for (int i = 0; i < n; ++i)
      (((i % 2 == 0) == bar_first) ? l.guard_bars : l.guard_spaces).push_back(at + i);
    at += n;
  };
  auto characters = [&](int n) {
    for (int i = 0; i < n; ++i, at += kEanCharacterModules) l.starts.push_back(at);
  };
  guard(3, true);
  characters(per_side);
  if (upc_e) {
    guard(6, false);  // after L and G characters, which end with a bar
  } else {
    guard(5, false);
    characters(per_side);
    guard(3, true);  // after R characters, which end with a space
  }
  l.modules = at;
  l.elements = l.guard_bars.size() + l.guard_spaces.size() + 4 * l.starts.size();
  return l;
}

}  // namespace flutterscan::reader
