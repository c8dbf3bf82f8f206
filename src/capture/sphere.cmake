# clayfit_sphere: sphere silhouettes (OpenCV) and their triangulation.
# add_library(clayfit_sphere STATIC ...) and its link libraries go here.
