#include "session/second_pass_tries.hpp"

#include <array>
#include <sstream>
#include <utility>

namespace flutterscan::session {
namespace {

constexpr std::array<std::pair<const char*, bool SecondPassTries::*>, 4> kTries = {{
    {"bar-sums", &SecondPassTries::bar_sums},
    {"tv-on-sums", &SecondPassTries::tv_on_sums},
    {"fit", &SecondPassTries::fit},
    {"isotropic-tv", &SecondPassTries::isotropic_tv},
}};

std::string trimmed(const std::string& s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

}  // namespace

std::optional<SecondPassTries> parse_second_pass_tries(const std::string& names,
                                                       std::string& problem) {
  const std::string all = trimmed(names);
  if (all == "none") return SecondPassTries{false, false, false, false};
  if (all == "all") return SecondPassTries{true, true, true, true};
  SecondPassTries tries{false, false, false, false};
  std::istringstream in(names);
  for (std::string name; std::getline(in, name, ',');) {
    name = trimmed(name);
    bool known = false;
    for (const auto& [try_name, member] : kTries)
      if (name == try_name) {
        tries.*member = true;
        known = true;
      }
    if (!known) {
      problem =
          "'" + name + "' is not a second-pass try (" + kSecondPassTryNames + ", or none, or all)";
      return std::nullopt;
    }
  }
  if ((tries.tv_on_sums || tries.fit) && !tries.bar_sums) {
    problem = std::string(tries.fit ? "fit" : "tv-on-sums") +
              " works on the bar sums: it needs bar-sums too";
    return std::nullopt;
  }
  return tries;
}

std::string second_pass_tries_name(const SecondPassTries& tries) {
  std::string out;
  for (const auto& [name, member] : kTries)
    if (tries.*member) out += (out.empty() ? "" : ",") + std::string(name);
  return out.empty() ? "none" : out;
}

}  // namespace flutterscan::session
