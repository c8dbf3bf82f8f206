# clayfit_image: the OpenImageIO adapter (the only C++ here), colour
# decoding, environment maps.
add_library(clayfit_image STATIC image_io.cpp image_codec.c image_oiio.cpp image_exr_check.c image_check.c colour.c envmap.c
            jpeg_coding.c light_probe.c)
target_link_libraries(clayfit_image PUBLIC clayfit_core
                      PRIVATE OpenImageIO::OpenImageIO clayfit_warnings m)
