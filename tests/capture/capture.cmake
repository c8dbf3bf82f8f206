# Tests of the capture files, the loader and synthetic captures.
clayfit_c_test(test_capture_synth SOURCES capture/test_capture_synth.c
               LIBS clayfit_capture LABELS capture)
# synth --response (each curve's codes decode to the linear render) and
# --format jpg with EXIF exposures.
clayfit_c_test(test_synth_response SOURCES capture/test_synth_response.c
               LIBS clayfit_capture LABELS capture)
# synth --environment: a uniform map's Lambert sphere is albedo x Lw, the
# pixels are the loaded capture's lights summed through cf_eval, truth.json
# records the map, and bad options are refused.
clayfit_c_test(test_synth_environment SOURCES capture/test_synth_environment.c
               LIBS clayfit_capture LABELS capture)
clayfit_c_test(test_capture_file SOURCES capture/test_capture_file.c
               LIBS clayfit_capture LABELS capture)
target_include_directories(test_capture_file PRIVATE ${PROJECT_SOURCE_DIR}/src)

# The real COLMAP program on a synthetic capture (slow: about 30 s).
add_executable(test_colmap_reconstruction capture/test_colmap_reconstruction.c)
target_link_libraries(test_colmap_reconstruction PRIVATE clayfit_test_support clayfit_colmap
                      clayfit_warnings)
add_test(NAME test_colmap_reconstruction
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/capture/colmap_reconstruction.sh
                 $<TARGET_FILE:clayfit> $<TARGET_FILE:test_colmap_reconstruction>
                 ${CMAKE_CURRENT_BINARY_DIR}/colmap_reconstruction)
set_tests_properties(test_colmap_reconstruction PROPERTIES LABELS "capture;slow"
                     SKIP_RETURN_CODE 77)
clayfit_c_test(test_capture_exposure SOURCES capture/test_capture_exposure.c
               capture/ortho_scene.c LIBS clayfit_capture LABELS capture)
clayfit_c_test(test_capture_environment SOURCES capture/test_capture_environment.c
               capture/ortho_scene.c LIBS clayfit_capture LABELS capture
               ARGS ${CLAYFIT_SHARED_DATA})
clayfit_c_test(test_capture_silhouettes SOURCES capture/test_capture_silhouettes.c
               LIBS clayfit_capture LABELS capture)
clayfit_c_test(test_capture_diligent SOURCES capture/test_capture_diligent.c
               LIBS clayfit_capture LABELS capture
               ARGS ${CMAKE_CURRENT_SOURCE_DIR} ${CLAYFIT_SHARED_DATA})

# Bad input, one test each: a broken capture per case (make_bad_captures),
# `clayfit inspect` on it, its message (naming file and field) and exit 2.
add_executable(make_bad_captures capture/make_bad_captures.c)
target_link_libraries(make_bad_captures PRIVATE clayfit_capture clayfit_warnings)
set(BAD ${CMAKE_CURRENT_BINARY_DIR}/bad_captures)
add_test(NAME make_bad_captures COMMAND make_bad_captures ${BAD})
set_tests_properties(make_bad_captures PROPERTIES LABELS capture FIXTURES_SETUP bad_captures)

# bad_capture(case regex): inspect BAD/case/capture.json, expect exit 2.
function(bad_capture case regex)
  add_test(NAME capture_bad_${case}
           COMMAND ${CHECK} --exit 2 --stderr "${regex}" --
                   ${CLAYFIT} inspect --no-overlays ${BAD}/${case}/capture.json)
  set_tests_properties(capture_bad_${case} PROPERTIES LABELS capture
                       FIXTURES_REQUIRED bad_captures)
endfunction()
bad_capture(missing_image "missing_image/images/001.exr.*(no such file|not found|does not exist)")
bad_capture(wrong_size "wrong_size/images/001.exr: the image is 80 x 60 pixels but its COLMAP camera 1 is 96 x 72")
bad_capture(truncated_bin "camera.model.*images.bin: byte [0-9]+: .*field")
bad_capture(unknown_camera "camera.model.*cameras.txt:[0-9]+.*PINHOLE_WITH_WOBBLE")
bad_capture(nan_exr "nan_exr/images/000.exr: .*NaN at pixel \\(20, 10\\), channel 1")
bad_capture(wrong_type "capture.json: lights: expected an array, got an object")
bad_capture(missing_field "capture.json: \\(top level\\): missing required key 'colour'")
bad_capture(missing_mask "missing_mask/nope.png.*(no such file|not found|does not exist)")
bad_capture(mask_size "mask_size/mask.png: the mask is 80 x 60 pixels but .*000.exr is 96 x 72")
bad_capture(unseen_sphere "capture.json: geometry: the sphere \\(centre 0 0 -40, radius 1\\) is seen by none of the 2 cameras")

# What synth and inspect write, against data_schema/; the capture files in
# tests/ too.
set(VALIDATE ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/cli/validate_json.py)
set(SMALL ${CMAKE_CURRENT_BINARY_DIR}/cli_synth_small)
add_test(NAME cli_synth_small COMMAND ${CLAYFIT} --quiet synth -o ${SMALL} --images 3
         --size 128x96 --format png16 --masks --param albedo=0.7,0.5,0.3)
set_tests_properties(cli_synth_small PROPERTIES LABELS "cli;capture" FIXTURES_SETUP synth_small)
add_test(NAME cli_synth_outputs_valid
         COMMAND ${VALIDATE} ${SMALL}/capture.json=${SCHEMA}/capture.schema.json
                 ${SMALL}/truth.json=${SCHEMA}/truth.schema.json
                 ${CMAKE_CURRENT_SOURCE_DIR}/diligent_ball.capture.json=${SCHEMA}/capture.schema.json
                 ${CMAKE_CURRENT_SOURCE_DIR}/diligent_ball_circle.capture.json=${SCHEMA}/capture.schema.json)
set_tests_properties(cli_synth_outputs_valid PROPERTIES LABELS "cli;capture"
                     FIXTURES_REQUIRED synth_small)
add_test(NAME cli_inspect_json
         COMMAND ${CHECK} --schema ${SCHEMA}/inspect.schema.json
                 --expect "doc['observations'] > 1000 and len(doc['images']) == 3"
                 --expect "len(doc['overlays']) == 3 and doc['camera'] == 'colmap'"
                 -- ${CLAYFIT} --quiet inspect --json -o ${SMALL}/overlays ${SMALL}/capture.json)
set_tests_properties(cli_inspect_json PROPERTIES LABELS "cli;capture" FIXTURES_REQUIRED synth_small)
# synth --format jpg --response: what it writes is valid, and its bad options
set(SYNTH_JPG ${CMAKE_CURRENT_BINARY_DIR}/cli_synth_jpg)
add_test(NAME cli_synth_jpg COMMAND ${CLAYFIT} --quiet synth -o ${SYNTH_JPG} --images 2
         --size 96x72 --format jpg --quality 80 --exif-exposures --response filmic)
set_tests_properties(cli_synth_jpg PROPERTIES LABELS "cli;capture" FIXTURES_SETUP synth_jpg)
add_test(NAME cli_synth_jpg_valid
         COMMAND ${VALIDATE} ${SYNTH_JPG}/capture.json=${SCHEMA}/capture.schema.json
                 ${SYNTH_JPG}/truth.json=${SCHEMA}/truth.schema.json)
set_tests_properties(cli_synth_jpg_valid PROPERTIES LABELS "cli;capture"
                     FIXTURES_REQUIRED synth_jpg)
clayfit_cli_test(error_synth_response --exit 2
  --stderr "--response: 'log' is not a response curve \\(linear, srgb, gamma2.2, filmic\\)" --
  ${CLAYFIT} synth -o ${CMAKE_CURRENT_BINARY_DIR}/never --response log)
clayfit_cli_test(error_synth_exif_png --exit 2 --stderr "EXIF exposures need the jpg format" --
  ${CLAYFIT} synth -o ${CMAKE_CURRENT_BINARY_DIR}/never --exif-exposures)
clayfit_cli_test(error_synth_out_of_range --exit 2
  --stderr "parameter film_f0 of model clay is 0.5, outside its range" --
  ${CLAYFIT} synth -o ${CMAKE_CURRENT_BINARY_DIR}/never --param film_f0=0.5)
include(capture/synth_environment.cmake)
# The brightest radiance the ladder reflects per unit irradiance (the upper
# bound of the screen of photo values, docs/captures.md): a search over the
# models, their parameter ranges and the light's direction stays below it.
clayfit_c_test(test_radiance_bound SOURCES capture/test_radiance_bound.c
               LIBS clayfit_capture LABELS capture)
target_include_directories(test_radiance_bound PRIVATE ${PROJECT_SOURCE_DIR}/src)
