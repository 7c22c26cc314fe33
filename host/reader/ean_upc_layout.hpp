#pragma once
// The EAN/UPC symbols (ISO/IEC 15420) as the reader knows them: where the
// guards and symbol characters lie (the read record's modules and elements,
// code_measure), the characters' widths and EAN-13's first-digit parities
// (the bar-pattern fit), and which of ZXing's formats they are. A symbol
// character is two bars and two spaces over seven modules; every guard
// element is one module wide.

#include <array>
#include <cstddef>
#include <optional>
#include <string_view>
#include <vector>

namespace flutterscan::reader {

/// \brief Modules of one symbol character.
inline constexpr int kEanCharacterModules = 7;

/// \brief The widths of the ten "L" characters (digits 0-9; space, bar, space,
/// bar). An "R" character has the same widths starting with a bar, a "G"
/// character them reversed starting with a space.
inline constexpr std::array<std::array<int, 4>, 10> kEanLWidths = {{{3, 2, 1, 1},
                                                                    {2, 2, 2, 1},
                                                                    {2, 1, 2, 2},
                                                                    {1, 4, 1, 1},
                                                                    {1, 1, 3, 2},
                                                                    {1, 2, 3, 1},
                                                                    {1, 1, 1, 4},
                                                                    {1, 3, 1, 2},
                                                                    {1, 2, 1, 3},
                                                                    {3, 1, 1, 2}}};

/// \brief An EAN-13's left-half parities (L or G, 1 for G) for each first digit.
inline constexpr std::array<std::array<int, 6>, 10> kEan13FirstDigitParities = {
    {{0, 0, 0, 0, 0, 0},
     {0, 0, 1, 0, 1, 1},
     {0, 0, 1, 1, 0, 1},
     {0, 0, 1, 1, 1, 0},
     {0, 1, 0, 0, 1, 1},
     {0, 1, 1, 0, 0, 1},
     {0, 1, 1, 1, 0, 0},
     {0, 1, 0, 1, 0, 1},
     {0, 1, 0, 1, 1, 0},
     {0, 1, 1, 0, 1, 0}}};

/// \brief Where one EAN/UPC symbology's guards and characters lie, in modules
/// from the start guard's first bar: the start guard (bar, space, bar), the
/// left characters, the centre guard (space, bar, space, bar, space; UPC-E has
/// none), the right characters, the end guard (bar, space, bar; UPC-E's is
/// space, bar, space, bar, space, bar).
struct EanUpcLayout {
  int modules = 0;                ///< start guard to end guard: 95 (EAN-13, UPC-A), 67, 51
  std::size_t elements = 0;       ///< bars and spaces, first bar to last: 59, 43, 33
  std::vector<int> starts;        ///< each character's first module, left to right
  int left_characters = 0;        ///< before the centre guard (UPC-E: every one)
  bool both_parities = false;     ///< a left character may be L or G (all but EAN-8's)
  std::vector<int> guard_bars;    ///< the guards' bar modules, ascending
  std::vector<int> guard_spaces;  ///< the guards' space modules, ascending
};

/// \brief Whether ZXing's format name `format` is one of EAN-13, UPC-A, EAN-8, UPC-E.
bool is_ean_upc(std::string_view format);

/// \brief The layout of ZXing's format `format` (is_ean_upc()); nullopt for any other.
std::optional<EanUpcLayout> ean_upc_layout(std::string_view format);

}  // namespace flutterscan::reader
