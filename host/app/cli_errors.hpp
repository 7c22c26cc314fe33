#pragma once
// Exceptions used at the CLI edge only: main() maps them to exit codes.

#include <stdexcept>

namespace flutterscan::app {

/// \brief Bad usage or bad input: exit 2, message names what and where.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// \brief The work itself failed (a file could not be written, ...): exit 1.
struct RuntimeFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace flutterscan::app
