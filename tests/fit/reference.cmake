# A reference target of known albedo sets the scale of a capture with
# relative radiometry (issue 4): the loader's scale and refusals
# (test_capture_reference), and what it buys the fit.

# The loader: the scale from synth's grey card, every bad reference block
# refused with its JSON path; the bad capture files stay in REF_CASES.
set(REF_CASES ${CMAKE_CURRENT_BINARY_DIR}/capture_reference)
clayfit_c_test(test_capture_reference SOURCES capture/test_capture_reference.c
               LIBS clayfit_capture LABELS capture ARGS ${REF_CASES})
target_include_directories(test_capture_reference PRIVATE ${PROJECT_SOURCE_DIR}/src)
set_tests_properties(test_capture_reference PROPERTIES FIXTURES_SETUP reference_cases)
# through the command line: exit status 2, the file and JSON path named
function(bad_reference case regex)
  add_test(NAME capture_bad_reference_${case}
           COMMAND ${CHECK} --exit 2 --stderr "${case}.json: ${regex}" --
                   ${CLAYFIT} --quiet inspect --no-overlays ${REF_CASES}/reference/${case}.json)
  set_tests_properties(capture_bad_reference_${case} PROPERTIES LABELS "cli;capture"
                       FIXTURES_REQUIRED reference_cases)
endfunction()
bad_reference(absolute "reference: a reference target sets the scale .* needs \"radiometry\": \"relative\"")
bad_reference(region_outside "reference.region: \\[190, 140, 210, 150\\] reaches outside 000.exr, which is 200 x 150 pixels")
bad_reference(zero_normal "reference.normal: a direction needs a finite, non-zero length")
bad_reference(albedo_above_1 "reference.albedo: 1.5 is outside .0, 1.")
bad_reference(unknown_image "reference.image: '100.exr' is not one of the capture's 8 images")
bad_reference(point_light_without_point "reference: the lights include a point light or a flash")
bad_reference(no_usable_pixels "reference.region: only 0 of its [0-9]+ pixels in 000.exr are usable \\([0-9]+ clipped\\)")

# The fit: a noise-free M2 capture (f0 0.05, not the 0.04 the fit would
# assume) whose flash intensity is given 0.37 times the true one, with a
# grey card of albedo 0.5 in image 0; and the same capture without the card.
set(FIT_REF ${CMAKE_CURRENT_BINARY_DIR}/cli_fit_reference)
add_test(NAME cli_synth_reference COMMAND ${CLAYFIT} --quiet synth -o ${FIT_REF} --model M2
         --images 8 --size 200x150 --format exr --no-noise --supersample 1
         --param albedo=0.6,0.4,0.3 --param roughness=0.3 --param f0=0.05
         --param diffuse_roughness=0.3 --reference 0.5)
add_test(NAME cli_synth_reference_dropped
         COMMAND ${CLAYFIT_PYTHON} -c
         "import json, sys; d = json.load(open(sys.argv[1])); del d['reference']; json.dump(d, open(sys.argv[2], 'w'), indent=2)"
         ${FIT_REF}/capture.json ${FIT_REF}/no_reference.json)
set_tests_properties(cli_synth_reference PROPERTIES LABELS "cli;fit" FIXTURES_SETUP fit_reference)
set_tests_properties(cli_synth_reference_dropped PROPERTIES LABELS "cli;fit"
                     FIXTURES_REQUIRED fit_reference FIXTURES_SETUP fit_no_reference)
add_test(NAME cli_synth_reference_valid
         COMMAND ${VALIDATE} ${FIT_REF}/capture.json=${SCHEMA}/capture.schema.json
                 ${FIT_REF}/truth.json=${SCHEMA}/truth.schema.json)
set_tests_properties(cli_synth_reference_valid PROPERTIES LABELS "cli;fit"
                     FIXTURES_REQUIRED fit_reference)
clayfit_cli_test(inspect_reference --schema ${SCHEMA}/inspect.schema.json
  --expect "doc['radiometry'] == 'from_reference'"
  --expect "abs(doc['reference']['scale'] * 0.37 - 1) < 1e-6 and doc['reference']['spread'] < 1e-6"
  --expect "doc['reference']['pixels'] >= 16 and doc['warnings'] == []"
  -- ${CLAYFIT} --quiet inspect --json --no-overlays ${FIT_REF}/capture.json)
set_tests_properties(cli_inspect_reference PROPERTIES LABELS "cli;fit" FIXTURES_REQUIRED fit_reference)
# with the card: the lights absolute, F0 fitted, the truth recovered (the
# capture has one sample per pixel: the fit evaluates pixel centres too)
clayfit_cli_test(fit_reference --schema ${SCHEMA}/fit.schema.json
  --json-file ${FIT_REF}/with/fit.json
  --expect "doc['capture']['radiometry'] == 'from_reference'"
  --expect "abs(doc['capture']['reference']['scale'] * 0.37 - 1) < 1e-6"
  --expect "doc['scale'] == {'value': 1.0, 'sd': 0.0, 'fitted': False} and doc['held'] == []"
  --expect "doc['params']['f0']['status'] == 'fitted' and abs(doc['params']['f0']['value'] - 0.05) < 1e-4"
  --expect "all(abs(a - b) < 1e-4 for a, b in zip(doc['params']['albedo']['value'], [0.6, 0.4, 0.3]))"
  --expect "abs(doc['params']['roughness']['value'] - 0.3) < 1e-4"
  -- ${CLAYFIT} --quiet fit ${FIT_REF}/capture.json -o ${FIT_REF}/with --model M2
     --footprint centre)
set_tests_properties(cli_fit_reference PROPERTIES LABELS "cli;fit" FIXTURES_REQUIRED fit_reference)
# without it: F0 held at 0.04 for the scale, and the albedo 22 % off
clayfit_cli_test(fit_reference_dropped --schema ${SCHEMA}/fit.schema.json
  --json-file ${FIT_REF}/without/fit.json
  --expect "doc['capture']['radiometry'] == 'relative' and 'reference' not in doc['capture']"
  --expect "doc['params']['f0']['value'] == 0.04 and doc['params']['f0']['status'].startswith('held')"
  --expect "doc['scale']['fitted'] and doc['params']['albedo']['value'][0] < 0.6 - 0.05"
  -- ${CLAYFIT} --quiet fit ${FIT_REF}/no_reference.json -o ${FIT_REF}/without --model M2
     --footprint centre)
set_tests_properties(cli_fit_reference_dropped PROPERTIES LABELS "cli;fit"
                     FIXTURES_REQUIRED fit_no_reference)
clayfit_cli_test(error_synth_reference --exit 2 --stderr "--reference: the albedo 1.5 is outside .0, 1."
  -- ${CLAYFIT} synth -o ${CMAKE_CURRENT_BINARY_DIR}/never --reference 1.5)
