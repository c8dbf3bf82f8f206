# The fuzz targets' code on their seeds and on the inputs that once found a
# bug (tests/fuzz/regressions/fuzz_TARGET), compiled normally: each is a test
# here, in Release and under ASan+UBSan. scripts/fuzz.sh builds the same
# targets with libFuzzer (tests/fuzz/fuzz.mk) and fuzzes them.
set(FUZZ_DIR ${CMAKE_CURRENT_SOURCE_DIR}/fuzz)

# clayfit_fuzz_inputs(target label source LIBS... DIRS...): the test
# fuzz_inputs_<target> runs fuzz/<source> over DIRS and, when it exists,
# fuzz/regressions/fuzz_<target> (scripts/fuzz.sh's name for the target).
function(clayfit_fuzz_inputs target label source)
  cmake_parse_arguments(F "" "" "LIBS;DIRS" ${ARGN})
  add_executable(fuzz_run_${target} fuzz/${source} fuzz/fuzz_main.c)
  target_link_libraries(fuzz_run_${target} PRIVATE ${F_LIBS} clayfit_warnings)
  target_include_directories(fuzz_run_${target} PRIVATE ${PROJECT_SOURCE_DIR}/src)
  set(dirs ${F_DIRS})
  if(EXISTS ${FUZZ_DIR}/regressions/fuzz_${target})
    list(APPEND dirs ${FUZZ_DIR}/regressions/fuzz_${target})
  endif()
  add_test(NAME fuzz_inputs_${target} COMMAND fuzz_run_${target} ${dirs})
  set_tests_properties(fuzz_inputs_${target} PROPERTIES LABELS "${label};fuzz")
endfunction()

clayfit_fuzz_inputs(capture_spec capture fuzz_capture_spec.c LIBS clayfit_capture
                    DIRS ${FUZZ_DIR}/seeds/capture_spec)
clayfit_fuzz_inputs(text capture fuzz_text.c LIBS clayfit_capture
                    DIRS ${FUZZ_DIR}/seeds/text)
clayfit_fuzz_inputs(fit_file fit fuzz_fit_file.c LIBS clayfit_fit_read
                    DIRS ${FUZZ_DIR}/seeds/fit_file)

# the images: tiny ones in every format, written by make_image_seeds first
add_executable(make_image_seeds fuzz/make_image_seeds.c)
target_link_libraries(make_image_seeds PRIVATE clayfit_image clayfit_warnings)
set(IMAGE_SEEDS ${CMAKE_CURRENT_BINARY_DIR}/fuzz_image_seeds)
add_test(NAME fuzz_image_seeds COMMAND make_image_seeds ${IMAGE_SEEDS})
set_tests_properties(fuzz_image_seeds PROPERTIES LABELS "capture;fuzz"
                     FIXTURES_SETUP fuzz_image_seeds)
clayfit_fuzz_inputs(image capture fuzz_image.cpp LIBS clayfit_image
                    DIRS ${IMAGE_SEEDS})
set_tests_properties(fuzz_inputs_image PROPERTIES FIXTURES_REQUIRED fuzz_image_seeds)

# what fuzz_image found inside OpenEXR, refused before OpenEXR sees it
clayfit_c_test(test_exr_headers SOURCES fuzz/test_exr_headers.c LIBS clayfit_image
               LABELS capture ARGS ${FUZZ_DIR}/regressions/fuzz_image)
target_include_directories(test_exr_headers PRIVATE ${PROJECT_SOURCE_DIR}/src)
