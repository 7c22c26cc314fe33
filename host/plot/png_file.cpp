#include "plot/png_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace flutterscan::plot {
namespace {

struct PngSink {
  int fd;
  int error = 0;  ///< errno of a failed write
};

cairo_status_t write_to_sink(void* closure, const unsigned char* data, unsigned int length) {
  auto* sink = static_cast<PngSink*>(closure);
  while (length > 0) {
    const ssize_t written = ::write(sink->fd, data, length);
    if (written < 0) {
      if (errno == EINTR) continue;
      sink->error = errno;
      return CAIRO_STATUS_WRITE_ERROR;
    }
    data += written;
    length -= static_cast<unsigned int>(written);
  }
  return CAIRO_STATUS_SUCCESS;
}

/// Creates a new, uniquely named file beside `path`; returns its descriptor (or -1 with errno).
int create_temporary(const std::string& path, std::string& temporary) {
  static std::atomic<unsigned> counter{0};
  for (int attempt = 0; attempt < 100; ++attempt) {
    temporary = path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
    const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0 || errno != EEXIST) return fd;
  }
  return -1;
}

}  // namespace

std::string write_surface_png(cairo_surface_t* surface, const std::string& path) {
  std::string temporary;
  const int fd = create_temporary(path, temporary);
  if (fd < 0) {
    const int error = errno;
    const std::filesystem::path directory = std::filesystem::path(path).parent_path();
    if (error == ENOENT && !directory.empty()) {
      return "directory '" + directory.string() + "' does not exist";
    }
    return std::string("cannot create a temporary file beside it: ") + std::strerror(error);
  }
  PngSink sink{fd};
  const cairo_status_t status = cairo_surface_write_to_png_stream(surface, write_to_sink, &sink);
  std::string failure;
  if (status != CAIRO_STATUS_SUCCESS) {
    failure = std::string("writing PNG data failed: ") +
              (sink.error != 0 ? std::strerror(sink.error) : cairo_status_to_string(status));
  } else if (::fsync(fd) != 0) {
    failure = std::string("fsync failed: ") + std::strerror(errno);
  }
  if (::close(fd) != 0 && failure.empty()) {
    failure = std::string("closing the file failed: ") + std::strerror(errno);
  }
  if (failure.empty() && std::rename(temporary.c_str(), path.c_str()) != 0) {
    failure = std::string("renaming '") + temporary + "' over it failed: " + std::strerror(errno);
  }
  if (!failure.empty()) ::unlink(temporary.c_str());
  return failure;
}

}  // namespace flutterscan::plot
