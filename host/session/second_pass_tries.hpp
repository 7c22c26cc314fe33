#pragma once
// The cascade's second-pass tries (second_pass.hpp), by name. Each window the
// first pass read nothing in is deblurred again by tv and read; beyond that,
// each try below runs where the ones before it read nothing, and each can be
// switched off (processing.second_pass_tries, `flutterscan deblur --tries`):
// - "bar-sums": a linear code's rows summed along its bars, deblurred by joint
//   Wiener and read by the decoders;
// - "tv-on-sums": the same sums deblurred by tv and read, each value checked
//   against joint Wiener's sums (reader::fit_bar_pattern); needs bar-sums;
// - "fit": an EAN-13 read on joint Wiener's sums by fitting the symbol itself
//   (reader::read_ean13_by_fit), no decoder involved; needs bar-sums;
// - "isotropic-tv": the window deblurred by tv with the same weight across the
//   motion as along it, read for every symbology.
// A value a try reports carries its name (reader::DecodedCode::pass).

#include <optional>
#include <string>

namespace flutterscan::session {

/// \brief Which tries run; the defaults are kDefaultSecondPassTries.
struct SecondPassTries {
  bool bar_sums = true;
  bool tv_on_sums = false;
  bool fit = false;
  bool isotropic_tv = true;

  bool operator==(const SecondPassTries&) const = default;
};

/// \brief The tries a line runs unless it names others: those whose values a
/// decoder reads on the picture (docs/algorithms.md, "The second pass's tries").
inline constexpr const char* kDefaultSecondPassTries = "bar-sums,isotropic-tv";

/// \brief Every try's name, in the order the second pass runs them.
inline constexpr const char* kSecondPassTryNames = "bar-sums, tv-on-sums, fit, isotropic-tv";

/// \brief The tries `names` lists (comma-separated names of kSecondPassTryNames,
/// "none" for none, "all" for all); nullopt if a name is unknown or a try
/// lacks one it needs (tv-on-sums and fit need bar-sums). `problem` says which.
std::optional<SecondPassTries> parse_second_pass_tries(const std::string& names,
                                                       std::string& problem);

/// \brief `tries` as parse_second_pass_tries() reads them ("none" where none).
std::string second_pass_tries_name(const SecondPassTries& tries);

}  // namespace flutterscan::session
