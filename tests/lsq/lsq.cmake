# Tests of src/lsq: the solver's C interface and its devices, each on a
# problem small enough to know the answer.
clayfit_c_test(test_lsq_layer SOURCES lsq/test_lsq_layer.c LIBS clayfit_lsq LABELS lsq)
clayfit_c_test(test_lsq_release_radius SOURCES lsq/test_lsq_release_radius.c LIBS clayfit_lsq
               LABELS lsq)
