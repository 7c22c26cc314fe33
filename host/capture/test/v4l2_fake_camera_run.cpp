// v4l2_fake_camera_run COMMAND [ARGS...]: runs COMMAND with the fake V4L2
// camera of v4l2_fake_device.hpp attached as /dev/video0 (default
// configuration: 64x48, SRGGB10/RGB24/YUYV, UVC-like controls), under
// umockdev's preload library, and exits with COMMAND's exit status. Lets the
// real flutterscan binary be tested against a camera, e.g.
//   v4l2_fake_camera_run build/bin/flutterscan cameras
// Exit 77 when umockdev is missing, 2 without a command, 1 when the command
// cannot run or dies of a signal.

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>

#include "umockdev_reexec.hpp"
#include "v4l2_fake_device.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: v4l2_fake_camera_run COMMAND [ARGS...]\n");
    return 2;
  }
  if (!flutterscan::capture::testing::run_under_umockdev(argc, argv)) return 77;
  try {
    flutterscan::capture::testing::FakeV4l2Device device({});
    const pid_t child = ::fork();
    if (child == 0) {
      ::execvp(argv[1], argv + 1);
      std::fprintf(stderr, "v4l2_fake_camera_run: cannot run %s: %s\n", argv[1],
                   std::strerror(errno));
      ::_exit(127);
    }
    int status = 0;
    while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
    }
    if (WIFEXITED(status)) return WEXITSTATUS(status);
    std::fprintf(stderr, "v4l2_fake_camera_run: %s died of signal %d\n", argv[1], WTERMSIG(status));
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "v4l2_fake_camera_run: %s\n", e.what());
    return 1;
  }
}
