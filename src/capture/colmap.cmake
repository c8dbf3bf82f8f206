# clayfit_colmap: COLMAP sparse models (text, binary) and camera models.
# add_library(clayfit_colmap STATIC ...) and its link libraries go here.
