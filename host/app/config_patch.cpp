#include "app/config_patch.hpp"

#include <cstdio>
#include <sstream>

namespace flutterscan::app {
namespace {

std::string trim(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return {};
  const auto end = s.find_last_not_of(" \t\r");
  return s.substr(begin, end - begin + 1);
}

/// The table a header line opens ("[optics]" -> "optics"), or empty.
std::string header_of(const std::string& line) {
  const std::string t = trim(line);
  if (t.size() < 3 || t[0] != '[' || t[1] == '[') return {};
  const auto close = t.find(']');
  if (close == std::string::npos) return {};
  return trim(t.substr(1, close - 1));
}

/// The key a `key = value` line sets, or empty.
std::string key_of(const std::string& line) {
  const std::string t = trim(line);
  if (t.empty() || t[0] == '#') return {};
  const auto equals = t.find('=');
  if (equals == std::string::npos) return {};
  return trim(t.substr(0, equals));
}

/// Square brackets opened minus closed on `line`, outside strings and comments.
int bracket_balance(const std::string& line) {
  int balance = 0;
  bool in_string = false;
  for (char c : line) {
    if (c == '"') in_string = !in_string;
    if (in_string) continue;
    if (c == '#') break;
    if (c == '[') ++balance;
    if (c == ']') --balance;
  }
  return balance;
}

}  // namespace

std::string toml_number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  std::string s = text;
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // keep it a float
  return s;
}

std::string toml_number_array(const std::vector<double>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + toml_number(values[i]);
  return out + "]";
}

std::string toml_number_matrix(const std::vector<double>& values, int rows) {
  const std::size_t cols = rows > 0 ? values.size() / static_cast<std::size_t>(rows) : 0;
  std::string out = "[";
  for (int r = 0; r < rows; ++r) {
    const auto begin = values.begin() + static_cast<std::ptrdiff_t>(r * cols);
    out += (r ? ", " : "") +
           toml_number_array(std::vector<double>(begin, begin + static_cast<std::ptrdiff_t>(cols)));
  }
  return out + "]";
}

std::string patch_toml_table(const std::string& text, const std::string& table,
                             const std::vector<std::pair<std::string, std::string>>& values,
                             const std::string& comment) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  auto assignment = [&](const std::pair<std::string, std::string>& kv) {
    return kv.first + " = " + kv.second + (comment.empty() ? "" : "  # " + comment);
  };
  std::vector<bool> written(values.size(), false);
  std::vector<std::string> out;
  std::string current;
  std::size_t table_end = std::string::npos;  // index in `out` after the table's last line
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string header = header_of(lines[i]);
    if (!header.empty()) current = header;
    if (current == table && header.empty()) {
      const std::string key = key_of(lines[i]);
      bool replaced = false;
      for (std::size_t v = 0; v < values.size() && !key.empty(); ++v) {
        if (values[v].first != key) continue;
        // Skip the old value's continuation lines (a multi-line array).
        const auto equals = lines[i].find('=');
        int balance = bracket_balance(lines[i].substr(equals + 1));
        while (balance > 0 && i + 1 < lines.size()) balance += bracket_balance(lines[++i]);
        out.push_back(assignment(values[v]));
        written[v] = true;
        replaced = true;
        break;
      }
      if (!replaced) out.push_back(lines[i]);
      if (!trim(lines[i]).empty()) table_end = out.size();
      continue;
    }
    out.push_back(lines[i]);
    if (current == table && !header.empty()) table_end = out.size();
  }
  std::vector<std::string> missing;
  for (std::size_t v = 0; v < values.size(); ++v)
    if (!written[v]) missing.push_back(assignment(values[v]));
  if (!missing.empty()) {
    if (table_end == std::string::npos) {
      if (!out.empty() && !trim(out.back()).empty()) out.emplace_back();
      out.push_back("[" + table + "]");
      table_end = out.size();
    }
    out.insert(out.begin() + static_cast<std::ptrdiff_t>(table_end), missing.begin(),
               missing.end());
  }
  std::string result;
  for (const auto& line : out) result += line + "\n";
  return result;
}

}  // namespace flutterscan::app
