# clayfit_capture sources beyond lights.c: target_sources(clayfit_capture PRIVATE ...)
