# FindOpenImageIO: OpenImageIO's library and headers (libopenimageio-dev),
# as the imported target OpenImageIO::OpenImageIO. Debian 12's own
# OpenImageIOConfig.cmake refuses to load without the command-line tools
# (/usr/bin/iconvert, ...: openimageio-tools, which brings Qt 5: 41 more
# packages, 13 MB, that clayfit does not use), so the library is found here.
find_path(OpenImageIO_INCLUDE_DIR OpenImageIO/imageio.h)
find_path(OpenImageIO_Imath_INCLUDE_DIR ImathVec.h PATH_SUFFIXES Imath)
find_library(OpenImageIO_LIBRARY OpenImageIO)
find_library(OpenImageIO_Util_LIBRARY OpenImageIO_Util)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OpenImageIO REQUIRED_VARS OpenImageIO_LIBRARY
  OpenImageIO_Util_LIBRARY OpenImageIO_INCLUDE_DIR OpenImageIO_Imath_INCLUDE_DIR)
if(OpenImageIO_FOUND AND NOT TARGET OpenImageIO::OpenImageIO)
  add_library(OpenImageIO::OpenImageIO UNKNOWN IMPORTED)
  set_target_properties(OpenImageIO::OpenImageIO PROPERTIES
    IMPORTED_LOCATION ${OpenImageIO_LIBRARY}
    INTERFACE_INCLUDE_DIRECTORIES "${OpenImageIO_INCLUDE_DIR};${OpenImageIO_Imath_INCLUDE_DIR}"
    INTERFACE_LINK_LIBRARIES ${OpenImageIO_Util_LIBRARY})
endif()
