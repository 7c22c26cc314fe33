# OpenCV's core, imgproc and imgcodecs modules, the only ones the host uses,
# found by their files: OpenCV_INCLUDE_DIRS and OpenCV_LIBS (imported targets
# opencv_core, opencv_imgproc, opencv_imgcodecs), as OpenCV's own package sets
# them. Its package file (OpenCVConfig.cmake) comes only with Debian's
# libopencv-dev, which pulls the -dev packages of every OpenCV module (VTK,
# GDAL, Qt among them) and doubles a fresh machine's install; the three
# modules' own packages (libopencv-core-dev, libopencv-imgproc-dev,
# libopencv-imgcodecs-dev) hold everything the build needs.
find_path(OpenCV_INCLUDE_DIRS opencv2/core.hpp PATH_SUFFIXES opencv4 REQUIRED
          DOC "OpenCV's headers (Debian: libopencv-core-dev)")
set(OpenCV_LIBS "")
foreach(module core imgproc imgcodecs)
  find_library(OpenCV_${module}_LIBRARY opencv_${module} REQUIRED
               DOC "OpenCV's ${module} module (Debian: libopencv-${module}-dev)")
  add_library(opencv_${module} SHARED IMPORTED)
  set_target_properties(opencv_${module} PROPERTIES
    IMPORTED_LOCATION ${OpenCV_${module}_LIBRARY}
    INTERFACE_INCLUDE_DIRECTORIES ${OpenCV_INCLUDE_DIRS})
  list(APPEND OpenCV_LIBS opencv_${module})
endforeach()
