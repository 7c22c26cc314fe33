#pragma once
// Writes calibration results into a session config (TOML) without losing what
// the user wrote there: only the given keys of one table are replaced (their
// whole value, multi-line arrays included) or appended to the table, every
// other line and comment stays as it was, and a missing table is added at the end.

#include <string>
#include <utility>
#include <vector>

namespace flutterscan::app {

/// \brief `text` with `table`'s keys set to the given TOML values (already
/// formatted, e.g. "0.5" or "[1.0, 2.0]"), each replaced line ending in `comment`.
std::string patch_toml_table(const std::string& text, const std::string& table,
                             const std::vector<std::pair<std::string, std::string>>& values,
                             const std::string& comment);

/// \brief A TOML array of numbers, e.g. "[0.9, 0.08, 0.01]" (%.6g each).
std::string toml_number_array(const std::vector<double>& values);

/// \brief A TOML array of `rows` arrays of numbers from row-major `values`,
/// e.g. "[[0.9, 0.1], [0.1, 0.9]]".
std::string toml_number_matrix(const std::vector<double>& values, int rows);

/// \brief A TOML number (%.6g).
std::string toml_number(double value);

}  // namespace flutterscan::app
