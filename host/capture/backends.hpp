#pragma once
// The built-in camera backends. Each backend's source file defines its
// function; camera_backends() lists the ones compiled in (the CMake
// definitions FLUTTERSCAN_HAVE_V4L2, FLUTTERSCAN_HAVE_ARAVIS,
// FLUTTERSCAN_HAVE_LIBCAMERA say which).

#include "capture/camera_source.hpp"

namespace flutterscan::capture {

/// \brief "files:DIR": replays a folder of frames and their descriptors (files_camera.cpp).
CameraBackend files_camera_backend();
/// \brief "sim": the virtual conveyor (sim_camera.cpp).
CameraBackend sim_camera_backend();
/// \brief "v4l2:/dev/videoN" (v4l2_camera.cpp).
CameraBackend v4l2_camera_backend();
/// \brief "aravis:NAME": GenICam cameras through Aravis 0.8 (aravis_camera.cpp).
CameraBackend aravis_camera_backend();
/// \brief "libcamera:ID": cameras through libcamera 0.0.3 (libcamera_camera.cpp).
CameraBackend libcamera_camera_backend();

}  // namespace flutterscan::capture
