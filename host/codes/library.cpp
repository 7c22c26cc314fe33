#include "codes/library.hpp"

#include <array>

namespace flutterscan::codes {
namespace {

constexpr std::array<LibraryCode, 18> kLibrary = {{
    {"rect", "1111111111111111111111111111111111111111111111111111", 1,
     "conventional exposure: one LED on in every slot", false},
    {"rect-white", "7777777777777777777777777777777777777777777777777777", 3,
     "all three LEDs on in every slot (the rect-white scheme)", false},
    {"raskar", "1010000111000001010000110011110111010111001001100111", 1,
     "Raskar et al. 2006, the 52-chop flutter-shutter code", false},
    {"raskar-complement", "0101111000111110101111001100001000101000110110011000", 1,
     "Raskar's code with on and off swapped (seed, section 3)", false},
    {"raskar-white", "7070000777000007070000770077770777070777007007700777", 3,
     "all three LEDs flutter together with Raskar's code", false},
    {"thirds", "1111111111111111122222222222222222244444444444444444", 3,
     "contiguous thirds, 17/18/17 slots: three short exposures in a row", false},
    {"seed-random-100", "1211441122224144424114124442244121114441112412414142", 3,
     "seed figure 7: best of 100 random one-of-3 codes", false},
    {"seed-maxmin-1", "2212441414112412441224111241244244242212442211444144", 3,
     "seed section 5.1, max-min merit -21.4382 dB", true},
    {"seed-maxmin-2", "1212222141422244221122444224241121424422424241241242", 3,
     "seed section 5.1, max-min merit -21.5469 dB", true},
    {"seed-maxmin-3", "2211424222421411121144411124121212214214141122112142", 3,
     "seed section 5.1, max-min merit -21.7312 dB", true},
    {"seed-avgmin", "2212144111241224412411211221241444112124441212442242", 3,
     "seed second section 5.1, average-min merit -25.6353 dB", true},
    {"seed-pairs", "2221421124421222111122142141211244121242241114221211", 3,
     "seed third section 5.1, pairs merit -21.6372 dB (printed with a stray '1' at index 48)",
     true},
    {"found-joint", "4144414111414444112422141121412124421244141221422122", 3,
     "flutterscan annealing, 60 s, joint merit (E 3000 e-, c 3, read noise 4 e-): 204.1 e-", false},
    {"found-maxmin", "4114141211221111241144112141141124421111422222121211", 3,
     "flutterscan annealing, 60 s, max-min merit: -20.7890 dB", false},
    {"found-avgmin", "4111424412221114412411244211214144114242111421414212", 3,
     "flutterscan annealing, 60 s, average-min merit: -24.1266 dB", false},
    {"found-pairs", "2441114424142411441121422441121142141421411414121112", 3,
     "flutterscan annealing, 60 s, pairs merit: -20.7779 dB", false},
    {"found-single", "1001001101100110101011101011010000100011110100001110", 1,
     "flutterscan annealing, 60 s, single merit with 26 ones (pad 256): 0.0800", false},
    {"found-mse", "4242221144411121214241142422112112214412414144224412", 3,
     "flutterscan annealing, 60 s, mse merit (E 3000 e-, c 3, read noise 4 e-, eps 10)", false},
}};

}  // namespace

std::span<const LibraryCode> code_library() {
  return kLibrary;
}

std::optional<LibraryCode> find_library_code(std::string_view name) {
  for (const auto& entry : kLibrary)
    if (entry.name == name) return entry;
  return std::nullopt;
}

LedCode to_code(const LibraryCode& entry) {
  return LedCode::parse(entry.digits, entry.leds).value();
}

}  // namespace flutterscan::codes
