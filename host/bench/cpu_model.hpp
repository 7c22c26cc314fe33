#pragma once
// The CPU a benchmark ran on, printed beside its figures: the same code and
// machine size run 20-40% apart on the Intel and AMD hosts a line may have.

#include <fstream>
#include <string>

namespace flutterscan::bench {

/// \brief /proc/cpuinfo's first "model name", or "unknown CPU".
inline std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos && colon + 2 <= line.size()) return line.substr(colon + 2);
    }
  return "unknown CPU";
}

}  // namespace flutterscan::bench
