# Light probes from a chrome ball (src/capture/include/capture/light_probe.h, docs/lights.md
# "Light probe"): balls rendered in the real HDRIs, unwrapped and compared
# by their irradiance's spherical harmonics; 8-bit brackets merged back.
# It also writes the fixture of the `clayfit lights --probe` tests.
set(LIGHT_PROBE ${CMAKE_CURRENT_BINARY_DIR}/light_probe)
clayfit_c_test(test_light_probe SOURCES capture/test_light_probe.c capture/ortho_scene.c
               LIBS clayfit_image LABELS capture
               ARGS ${CLAYFIT_SHARED_DATA} ${LIGHT_PROBE})
target_include_directories(test_light_probe PRIVATE ${PROJECT_SOURCE_DIR}/src)
set_tests_properties(test_light_probe PROPERTIES FIXTURES_SETUP light_probe)

# `clayfit lights --probe` on that fixture (skipped without the HDRIs).
set(PROBE_DATA ${CLAYFIT_SHARED_DATA}/hdri/studio.exr)
set(BRACKETS ${LIGHT_PROBE}/bracket1.png ${LIGHT_PROBE}/bracket2.png ${LIGHT_PROBE}/bracket3.png)
set(BALL --circle 384 384 360)
# clayfit_probe_test(name CHECK-ARGS... -- CLAYFIT-ARGS...)
function(clayfit_probe_test name)
  add_test(NAME cli_lights_probe_${name} COMMAND ${CHECK} --skip-unless ${PROBE_DATA} ${ARGN})
  set_tests_properties(cli_lights_probe_${name} PROPERTIES LABELS "cli;capture"
                       FIXTURES_REQUIRED light_probe SKIP_RETURN_CODE 77)
endfunction()
clayfit_probe_test(hdr
  --expect "doc['width'] == 512 and doc['height'] == 256 and doc['photos'] == 1"
  --expect "abs(doc['invalid_fraction'] - 0.0111) < 0.001 and doc['ball']['radius'] == 360"
  --expect "os.path.getsize('${LIGHT_PROBE}/probe.exr') > 0"
  -- ${CLAYFIT} lights --probe ${LIGHT_PROBE}/ball.exr ${BALL} -o ${LIGHT_PROBE}/probe.exr --json)
set_tests_properties(cli_lights_probe_hdr PROPERTIES FIXTURES_SETUP light_probe_map)
clayfit_probe_test(mask
  --expect "doc['ball']['from'] == 'the mask' and abs(doc['ball']['radius'] - 360) < 0.5"
  --expect "abs(doc['ball']['cx'] - 384) < 0.5 and abs(doc['ball']['cy'] - 384) < 0.5"
  -- ${CLAYFIT} lights --probe ${LIGHT_PROBE}/ball.exr --mask ${LIGHT_PROBE}/mask.png
     -o ${LIGHT_PROBE}/probe_mask.exr --json)
clayfit_probe_test(brackets
  --expect "doc['photos'] == 3 and doc['encoding'] == 'srgb' and doc['saturated_everywhere'] == 0"
  --expect "all(abs(r / 4 - 1) < 0.02 for r in doc['measured_ratios'])"
  --expect "abs(doc['exposures'][0] - 1 / 60) < 1e-12"
  -- ${CLAYFIT} lights --probe ${BRACKETS} --exposures 1/60 4/60 16/60 ${BALL}
     -o ${LIGHT_PROBE}/probe_brackets.exr --json)
clayfit_probe_test(saturated --stderr "warning: [0-9]+ pixels are clipped in every bracket"
  -- ${CLAYFIT} lights --probe ${LIGHT_PROBE}/bracket3.png ${BALL} -o ${LIGHT_PROBE}/probe_sat.exr)
clayfit_probe_test(help --stdout "Debevec & Malik" --stdout "--exposures T"
  -- ${CLAYFIT} lights --probe --help)
# bad input: exit 2 and a message naming what is wrong
clayfit_probe_test(missing_bracket --exit 2
  --stderr "--probe and --exposures: 2 photos but 3 exposures.*a bracket is missing"
  -- ${CLAYFIT} lights --probe ${LIGHT_PROBE}/bracket1.png ${LIGHT_PROBE}/bracket3.png
     --exposures 1 4 16 ${BALL} -o ${LIGHT_PROBE}/never.exr)
clayfit_probe_test(missing_file --exit 2 --stderr "nothere.png: no such file"
  -- ${CLAYFIT} lights --probe ${LIGHT_PROBE}/bracket1.png ${LIGHT_PROBE}/nothere.png
     ${LIGHT_PROBE}/bracket3.png --exposures 1 4 16 ${BALL} -o ${LIGHT_PROBE}/never.exr)
clayfit_probe_test(gap --exit 2
  --stderr "bracket3.png \\(bracket 2\\) measures 1[0-9.]* times as bright as .*bracket1.png \\(bracket 1\\), but its exposure says 4 times"
  -- ${CLAYFIT} lights --probe ${LIGHT_PROBE}/bracket1.png ${LIGHT_PROBE}/bracket3.png
     --exposures 1 4 ${BALL} -o ${LIGHT_PROBE}/never.exr)
clayfit_probe_test(not_increasing --exit 2
  --stderr "exposures must increase strictly .*bracket3.png \\(bracket 3\\) has 4 after 16"
  -- ${CLAYFIT} lights --probe ${BRACKETS} --exposures 1 16 4 ${BALL} -o ${LIGHT_PROBE}/never.exr)
clayfit_probe_test(no_exif --exit 2
  --stderr "bracket1.png has no EXIF exposure time: give every bracket's with --exposures"
  -- ${CLAYFIT} lights --probe ${BRACKETS} ${BALL} -o ${LIGHT_PROBE}/never.exr)
clayfit_probe_test(sizes --exit 2 --stderr "normals.exr is 48 x 48 pixels but .*bracket1.png is 768 x 768: brackets must be photos of one size \\(from its header, before decoding\\)"
  -- ${CLAYFIT} lights --probe ${LIGHT_PROBE}/bracket1.png ${LIGHT_PROBE}/normals.exr
     --exposures 1 4 ${BALL} -o ${LIGHT_PROBE}/never.exr)
clayfit_probe_test(no_outline --exit 2 --stderr "give --mask MASK or --circle CX CY R"
  -- ${CLAYFIT} lights --probe ${LIGHT_PROBE}/ball.exr -o ${LIGHT_PROBE}/never.exr)
clayfit_probe_test(not_exr --exit 2 --stderr "name it \\*.exr"
  -- ${CLAYFIT} lights --probe ${LIGHT_PROBE}/ball.exr ${BALL} -o ${LIGHT_PROBE}/never.png)
# a capture whose `environment` light is the probe loads (16 lights from it)
add_test(NAME cli_lights_probe_inspect
         COMMAND ${CHECK} --skip-unless ${PROBE_DATA}
                 --expect "doc['lights_per_observation'] == 16 and doc['observations'] > 0"
                 -- ${CLAYFIT} --quiet inspect --json ${LIGHT_PROBE}/capture.json)
set_tests_properties(cli_lights_probe_inspect PROPERTIES LABELS "cli;capture"
                     FIXTURES_REQUIRED "light_probe;light_probe_map" SKIP_RETURN_CODE 77)
# 16-bit TIFF brackets whose exposures come from their EXIF
clayfit_probe_test(exif
  --expect "doc['exposures_from'] == 'EXIF' and abs(doc['exposures'][2] - 16 / 60) < 1e-6"
  --expect "all(abs(r / 4 - 1) < 0.02 for r in doc['measured_ratios'])"
  -- ${CLAYFIT} lights --probe ${LIGHT_PROBE}/bracket1.tif ${LIGHT_PROBE}/bracket2.tif
     ${LIGHT_PROBE}/bracket3.tif ${BALL} -o ${LIGHT_PROBE}/probe_exif.exr --json)
