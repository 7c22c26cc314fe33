#pragma once
// session_bench --soak MINUTES: does a long session keep its memory bounded?
// A session at 60 fps from the sim camera's ring of pre-rendered frames runs
// for MINUTES while a sampler reads the process's resident memory (RSS) and
// the heap in use (glibc's mallinfo2) every few seconds; the table reports the
// growth after the first minute as a least-squares slope in MB per hour, and
// the frames and objects the session counted (docs/benchmarks.md, "Soak").

#include <string>

#include "session/session_config.hpp"

namespace flutterscan::bench {

/// \brief Runs `config` (a paced sim session whose camera ends it) while sampling
/// memory every `sample_s` seconds; the samples also go to `csv` when it is not
/// empty. Prints the table; returns 0, or 1 when the session failed.
int soak_table(const session::SessionConfig& config, double sample_s, const std::string& csv);

}  // namespace flutterscan::bench
