# tests of the image component: the OpenImageIO adapter (every format both
# ways, orientation, EXIF, errors, the real DiLiGenT files), colour
# decoding, and environment maps reduced to lights (the real HDRIs).
clayfit_c_test(test_image_io SOURCES capture/test_image_io.c LIBS clayfit_image LABELS capture
               ARGS ${CLAYFIT_SHARED_DATA})
clayfit_c_test(test_colour SOURCES capture/test_colour.c LIBS clayfit_image LABELS capture)
clayfit_c_test(test_envmap SOURCES capture/test_envmap.c LIBS clayfit_image LABELS capture
               ARGS ${CLAYFIT_SHARED_DATA})
# a JPEG's coding from its markers, the in-memory round trip, damaged headers
clayfit_c_test(test_jpeg_coding SOURCES capture/test_jpeg_coding.c LIBS clayfit_image
               LABELS capture)
# the OpenEXR codec against OpenImageIO, bit for bit (the HDRIs, files
# image_oiio_write writes, files made with OpenEXR's API), its writer, damaged
# and hostile files; prints the read and write times
find_package(OpenEXR 3.1 CONFIG REQUIRED)
clayfit_c_test(test_image_exr SOURCES capture/test_image_exr.c capture/codec_support.c capture/exr_fixtures.cpp
               LIBS clayfit_image_oiio OpenEXR::OpenEXR LABELS capture ARGS ${CLAYFIT_SHARED_DATA})
target_include_directories(test_image_exr PRIVATE ${PROJECT_SOURCE_DIR}/src)
# the JPEG codec and EXIF against OpenImageIO: decoding, encoding, the
# round trip, hostile files (libjpeg writes the progressive and CMYK ones)
find_package(JPEG REQUIRED)
clayfit_c_test(test_image_jpeg SOURCES capture/test_image_jpeg.c capture/codec_support.c LIBS clayfit_image_oiio JPEG::JPEG
               LABELS capture ARGS ${CLAYFIT_SHARED_DATA})
# the PNG codec against OpenImageIO: made, written and real PNGs bit for
# bit, quantisation, damaged and hostile files, speed (printed)
find_package(PNG REQUIRED)
clayfit_c_test(test_image_png SOURCES capture/test_image_png.c capture/codec_support.c capture/test_image_png_make.c
               LIBS clayfit_image_oiio PNG::PNG LABELS capture ARGS ${CLAYFIT_SHARED_DATA})
# the PFM codec against OpenImageIO: made and real PFMs bit for bit, both
# byte orders, damaged headers and data
clayfit_c_test(test_image_pfm SOURCES capture/test_image_pfm.c capture/codec_support.c LIBS clayfit_image_oiio LABELS capture
               ARGS ${CLAYFIT_SHARED_DATA})
