# tests of the colmap component (the fuzz target is built by scripts/fuzz.sh)
clayfit_c_test(test_camera_models SOURCES capture/test_camera_models.c LIBS clayfit_colmap
               LABELS capture)
clayfit_c_test(test_colmap_io SOURCES capture/test_colmap_io.c LIBS clayfit_colmap
               LABELS capture)
clayfit_c_test(test_colmap_bad_input SOURCES capture/test_colmap_bad_input.c LIBS clayfit_colmap
               LABELS capture)
