# clayfit_image: the OpenImageIO adapter (the only C++ here), colour
# decoding, environment maps.
find_package(PNG REQUIRED)
add_library(clayfit_image STATIC image_io.cpp image_codec.c image_oiio.cpp image_exr_check.c image_check.c colour.c envmap.c
            jpeg_coding.c light_probe.c image_png.c image_pfm.c image_exif_pending.c)
target_link_libraries(clayfit_image PUBLIC clayfit_core
                      PRIVATE OpenImageIO::OpenImageIO PNG::PNG clayfit_warnings m)
