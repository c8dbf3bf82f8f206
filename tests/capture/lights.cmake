# clayfit lights: light directions from a chrome ball (src/capture/include/capture/chrome_ball.h,
# src/cli/cmd_lights.c; docs/lights.md).
clayfit_c_test(test_chrome_ball SOURCES capture/test_chrome_ball.c capture/chrome_render.c
               LIBS clayfit_capture m LABELS capture)
target_include_directories(test_chrome_ball PRIVATE ${PROJECT_SOURCE_DIR}/src)
clayfit_c_test(test_chrome_ball_uw SOURCES capture/test_chrome_ball_uw.c capture/chrome_render.c
               LIBS clayfit_capture m LABELS capture ARGS ${CLAYFIT_SHARED_DATA})
target_include_directories(test_chrome_ball_uw PRIVATE ${PROJECT_SOURCE_DIR}/src)

# The command: bad balls (errors, exit 2, nothing written; a light behind the
# ball a warning), captures with "intensities": "equal" (loaded as relative
# radiometry, fitted, the same as a file of ones; refused with absolute
# radiometry), a ball seen by a posed COLMAP camera (directions in the
# model's world frame), and uw_chrome's directions loaded by a capture
# (tests/cli/check_lights.py).
set(CHECK_LIGHTS ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/cli/check_lights.py)
add_test(NAME cli_lights_bad COMMAND ${CHECK_LIGHTS} bad ${CLAYFIT}
         ${CMAKE_CURRENT_BINARY_DIR}/cli_lights_bad)
add_test(NAME cli_lights_equal_intensities COMMAND ${CHECK_LIGHTS} equal ${CLAYFIT}
         ${CMAKE_CURRENT_BINARY_DIR}/cli_lights_equal)
add_test(NAME cli_lights_uw_chrome COMMAND ${CHECK_LIGHTS} uw ${CLAYFIT} ${CLAYFIT_SHARED_DATA}
         ${CMAKE_CURRENT_BINARY_DIR}/cli_lights_uw)
add_test(NAME cli_lights_colmap COMMAND ${CHECK_LIGHTS} colmap ${CLAYFIT}
         ${CMAKE_CURRENT_BINARY_DIR}/cli_lights_colmap)
# Hostile photos (issue 30): a PNG declaring 26000 x 26000 refused from its
# header before decoding, under a 2 GB address-space limit (not with the
# sanitizers: they reserve terabytes of address space); the decoded-bytes
# cap; and `lights --probe` inputs out of range and maps that are no light.
if(CLAYFIT_SANITIZE)
  set(LIGHTS_LIMIT --no-limit)
endif()
add_test(NAME cli_lights_bomb COMMAND ${CHECK_LIGHTS} bomb ${CLAYFIT}
         ${CMAKE_CURRENT_BINARY_DIR}/cli_lights_bomb ${LIGHTS_LIMIT})
add_test(NAME cli_lights_probe_bad COMMAND ${CHECK_LIGHTS} probe_bad ${CLAYFIT}
         ${CMAKE_CURRENT_BINARY_DIR}/cli_lights_probe_bad)
set_tests_properties(cli_lights_bad cli_lights_colmap cli_lights_bomb cli_lights_probe_bad
                     PROPERTIES LABELS "cli;capture")
set_tests_properties(cli_lights_equal_intensities PROPERTIES LABELS "cli;capture;fit")
set_tests_properties(cli_lights_uw_chrome PROPERTIES LABELS "cli;capture" SKIP_RETURN_CODE 77)
clayfit_cli_test(lights_help --stdout "usage: clayfit lights PHOTO" --stdout "directions.txt" --
  ${CLAYFIT} lights --help)
clayfit_cli_test(lights_no_outline --exit 2
  --stderr "clayfit lights: give the ball's outline: --mask MASK or --silhouette" --
  ${CLAYFIT} lights photo.png -o ${CMAKE_CURRENT_BINARY_DIR}/cli_lights_never)
clayfit_cli_test(lights_no_output --exit 2 --stderr "clayfit lights: -o DIR is required" --
  ${CLAYFIT} lights photo.png --silhouette)
clayfit_cli_test(lights_missing_photo --exit 2 --stderr "no-such-photo.png" --
  ${CLAYFIT} lights no-such-photo.png --silhouette -o ${CMAKE_CURRENT_BINARY_DIR}/cli_lights_never)
