#pragma once
// What went wrong talking to a controller, and the result type the device
// library returns (no exceptions below the CLI edge).

#include <string>
#include <utility>

#include "flutterscan/common/protocol.hpp"
#include "flutterscan/common/result.hpp"

namespace flutterscan::device {

/// \brief The kind of a device failure (the CLI maps bad input to exit 2, the rest to 1).
enum class ErrorKind {
  kNotFound,          ///< no controller (with that serial number) is connected
  kAmbiguous,         ///< several controllers and none named
  kGone,              ///< the device went away (unplugged, reset) or the link failed
  kTimeout,           ///< no reply in time, after every retry
  kRejected,          ///< the controller answered with an error status
  kProtocolMismatch,  ///< firmware speaks another protocol major
  kBadReply,          ///< a reply that does not parse
  kBadInput,          ///< the caller's arguments or file are wrong (exit 2)
  kAccess,            ///< the OS refused access (permissions, udev rules)
};

/// \brief A failure with a message that says what and where.
struct DeviceError {
  ErrorKind kind = ErrorKind::kGone;
  std::string message;
  protocol::Status status = protocol::Status::kOk;  ///< for kRejected
};

/// \brief Success without a value.
struct Done {};

/// \brief A value or a DeviceError (std::expected-like).
template <typename T>
using Expected = Result<T, DeviceError>;

/// \brief A failed Expected<T> of `kind` with `message`.
template <typename T = Done>
Expected<T> fail(ErrorKind kind, std::string message,
                 protocol::Status status = protocol::Status::kOk) {
  return Expected<T>::failure(DeviceError{kind, std::move(message), status});
}

/// \brief A failed Expected<T> carrying `error`.
template <typename T = Done>
Expected<T> fail(DeviceError error) {
  return Expected<T>::failure(std::move(error));
}

/// \brief A successful Expected<Done>.
inline Expected<Done> done() {
  return Expected<Done>::success(Done{});
}

}  // namespace flutterscan::device
