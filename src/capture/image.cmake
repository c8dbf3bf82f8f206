# clayfit_image: the OpenImageIO adapter (the only C++ here), the codecs
# (JPEG over libjpeg-turbo), colour decoding, environment maps.
find_package(JPEG REQUIRED)
add_library(clayfit_image STATIC image_io.cpp image_codec.c image_oiio.cpp image_exr_check.c image_check.c colour.c envmap.c
            image_jpeg.c image_exif.c jpeg_coding.c light_probe.c)
target_link_libraries(clayfit_image PUBLIC clayfit_core
                      PRIVATE OpenImageIO::OpenImageIO JPEG::JPEG clayfit_warnings m)
