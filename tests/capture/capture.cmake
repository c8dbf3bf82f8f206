# tests of the capture component: clayfit_c_test(test_... SOURCES capture/test_....c LIBS <library> LABELS capture)
