#pragma once
// ioctl() retried on EINTR, as every V4L2 call should be.

#include <sys/ioctl.h>

#include <cerrno>

namespace flutterscan::capture {

/// \brief ioctl(fd, request, arg), repeated while interrupted by a signal.
inline int v4l2_ioctl(int fd, unsigned long request, void* arg) {
  int result;
  do {
    result = ::ioctl(fd, request, arg);
  } while (result == -1 && errno == EINTR);
  return result;
}

}  // namespace flutterscan::capture
