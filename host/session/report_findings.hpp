#pragma once
// What went wrong in a session and what to do about it, in words, from its
// summary.json: the first screen of report.html (docs/session-output.md,
// "report.html"). Each finding names what happened with its figures and the
// step a line engineer takes next; a session where nothing went wrong gets
// one finding that says so.

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace flutterscan::session {

struct Finding {
  enum class Severity { kProblem, kWarning, kNote, kGood };
  Severity severity = Severity::kNote;
  std::string what;   ///< what happened, with its figures
  std::string to_do;  ///< what to do about it (empty: nothing to do)
};

/// \brief The findings of a session from its summary, problems first.
std::vector<Finding> report_findings(const nlohmann::json& summary);

/// \brief "problem", "warning", "note" or "good".
const char* severity_name(Finding::Severity severity);

}  // namespace flutterscan::session
