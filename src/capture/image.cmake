# clayfit_image: the OpenImageIO adapter, colour decoding, environment maps.
# add_library(clayfit_image STATIC ...) and its link libraries go here.
