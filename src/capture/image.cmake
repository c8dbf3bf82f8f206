# clayfit_image: images read and written (a dispatcher and a codec per
# format: PNG, JPEG, OpenEXR, PFM; image_codec.h), colour decoding,
# environment maps. Every other format goes through OpenImageIO, built as
# a module of its own (clayfit_oiio, below) that the dispatcher loads only
# when such a file appears: linked in, it cost every process 0.4 s of
# start (docs/images.md).
find_package(PNG REQUIRED)
find_package(JPEG REQUIRED)
find_package(OpenEXR 3.1 CONFIG REQUIRED)
add_library(clayfit_image STATIC image_io.c image_codec.c image_png.c image_pfm.c image_jpeg.c
            image_exif.c image_exr.cpp image_exr_check.c image_check.c colour.c envmap.c
            jpeg_coding.c light_probe.c)
target_link_libraries(clayfit_image PUBLIC clayfit_core
                      PRIVATE PNG::PNG JPEG::JPEG OpenEXR::OpenEXR ${CMAKE_DL_LIBS}
                      clayfit_warnings m)
target_compile_definitions(clayfit_image PRIVATE CLAYFIT_MODULE_DIR="${CLAYFIT_MODULE_DIR}")

# The general reader: OpenImageIO, when it is installed (the test command
# installs it; the demo does not need it). A module in the build's lib/
# folder (CLAYFIT_MODULE_DIR, CMakeLists.txt), which image_io.c opens by
# that path; it carries its own copy of what it calls of clayfit.
find_package(OpenImageIO)
if(OpenImageIO_FOUND)
  add_library(clayfit_oiio MODULE image_oiio.cpp image_codec.c ${PROJECT_SOURCE_DIR}/src/core/status.c)
  set_target_properties(clayfit_oiio PROPERTIES
    LIBRARY_OUTPUT_DIRECTORY ${CLAYFIT_MODULE_DIR} CXX_VISIBILITY_PRESET hidden
    C_VISIBILITY_PRESET hidden)
  target_include_directories(clayfit_oiio PRIVATE ${PROJECT_SOURCE_DIR}/include)
  target_link_libraries(clayfit_oiio PRIVATE OpenImageIO::OpenImageIO clayfit_warnings)
  # the codecs' tests hold each codec to OpenImageIO's reading and writing
  if(CLAYFIT_TESTS)
    add_library(clayfit_image_oiio STATIC image_oiio.cpp)
    target_link_libraries(clayfit_image_oiio PUBLIC clayfit_image
                          PRIVATE OpenImageIO::OpenImageIO clayfit_warnings)
  endif()
endif()
