# FindOpenCV: the OpenCV modules asked for (find_package(OpenCV COMPONENTS
# core imgproc ...)), each from its own Debian package (libopencv-core-dev,
# libopencv-imgproc-dev, libopencv-imgcodecs-dev). Debian ships OpenCV's own
# OpenCVConfig.cmake only in libopencv-dev, which installs every module and
# its dependencies (VTK, Qt, GStreamer: 122 more packages, 87 MB, beside the
# two modules clayfit links), so the modules are found one by one instead.
# Sets OpenCV_FOUND, OpenCV_INCLUDE_DIRS and OpenCV_LIBS (the libraries).
find_path(OpenCV_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4)
set(OpenCV_LIBS "")
foreach(module IN LISTS OpenCV_FIND_COMPONENTS)
  find_library(OpenCV_${module}_LIBRARY opencv_${module})
  find_path(OpenCV_${module}_INCLUDE_DIR opencv2/${module}.hpp PATH_SUFFIXES opencv4)
  if(OpenCV_${module}_LIBRARY AND OpenCV_${module}_INCLUDE_DIR)
    set(OpenCV_${module}_FOUND TRUE)
    list(APPEND OpenCV_LIBS ${OpenCV_${module}_LIBRARY})
  endif()
endforeach()
set(OpenCV_INCLUDE_DIRS ${OpenCV_INCLUDE_DIR})
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OpenCV REQUIRED_VARS OpenCV_INCLUDE_DIR HANDLE_COMPONENTS)
