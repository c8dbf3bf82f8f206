# synth --environment (docs/captures.md) through the command line: a
# capture lit by ../shared/data/hdri/studio.exr's 32 median-cut lights
# (skipped when the map is absent), its files valid, its fit recovering the
# truth, and the bad inputs refused with exit status 2.
set(ENV_MAP ${CLAYFIT_SHARED_DATA}/hdri/studio.exr)
set(SYNTH_ENV ${CMAKE_CURRENT_BINARY_DIR}/cli_synth_environment)
add_test(NAME cli_synth_environment
         COMMAND ${CHECK} --skip-unless ${ENV_MAP} --
                 ${CLAYFIT} --quiet synth -o ${SYNTH_ENV} --environment ${ENV_MAP}
                 --environment-lights 32 --images 8 --size 120x90 --format exr --model M2
                 --param albedo=0.6,0.4,0.3 --param roughness=0.3 --param f0=0.05
                 --param diffuse_roughness=0.3)
set_tests_properties(cli_synth_environment PROPERTIES LABELS "cli;capture"
                     FIXTURES_SETUP synth_environment SKIP_RETURN_CODE 77)
add_test(NAME cli_synth_environment_valid
         COMMAND ${CHECK} --skip-unless ${ENV_MAP} --schema ${SCHEMA}/truth.schema.json
                 --expect "doc['flash'] is None and doc['environment']['count'] == 32"
                 --expect "doc['environment']['rotation'] == [1, 0, 0, 0, 0, -1, 0, 1, 0]"
                 --expect "os.path.samefile(os.path.join('${SYNTH_ENV}', doc['environment']['file']), '${ENV_MAP}')"
                 -- ${CLAYFIT_PYTHON} -c "import sys; sys.stdout.write(open('${SYNTH_ENV}/truth.json').read())")
set_tests_properties(cli_synth_environment_valid PROPERTIES LABELS "cli;capture"
                     FIXTURES_REQUIRED synth_environment SKIP_RETURN_CODE 77)
add_test(NAME cli_synth_environment_capture_valid
         COMMAND ${CHECK} --skip-unless ${ENV_MAP} --schema ${SCHEMA}/capture.schema.json
                 --expect "[l['type'] for l in doc['lights']] == ['environment']"
                 --expect "doc['lights'][0]['count'] == 32 and len(doc['lights'][0]['rotation']) == 9"
                 -- ${CLAYFIT_PYTHON} -c "import sys; sys.stdout.write(open('${SYNTH_ENV}/capture.json').read())")
set_tests_properties(cli_synth_environment_capture_valid PROPERTIES LABELS "cli;capture"
                     FIXTURES_REQUIRED synth_environment SKIP_RETURN_CODE 77)
# The fit of that capture (the capture file's environment light, 32 lights
# per observation): every parameter within 2 sd of the truth or 0.3 % of it.
# Measured: at most 0.14 % (roughness, 7 sd): synth's 3 x 3 box samples
# against the fit's pixel footprint, not the lights.
set(ENV_TRUTH "{'albedo': [0.6, 0.4, 0.3], 'diffuse_roughness': [0.3], 'roughness': [0.3], 'f0': [0.05]}")
set(ENV_VALUES "[(v if isinstance(v, list) else [v]) for v in [doc['params'][k]['value'] for k in sorted(doc['params'])]]")
add_test(NAME cli_fit_synth_environment
         COMMAND ${CHECK} --skip-unless ${ENV_MAP} --json-file ${SYNTH_ENV}/fit/fit.json
                 --expect "doc['model']['code'] == 'M2' and doc['solver']['termination'] == 'CONVERGENCE'"
                 --expect "all(abs(v - t) <= max(2 * s, 0.003 * t) for k, p in doc['params'].items() for v, s, t in zip(p['value'] if isinstance(p['value'], list) else [p['value']], p['sd'] if isinstance(p['sd'], list) else [p['sd']], ${ENV_TRUTH}[k]))"
                 -- ${CLAYFIT} --quiet fit ${SYNTH_ENV}/capture.json -o ${SYNTH_ENV}/fit --model M2)
set_tests_properties(cli_fit_synth_environment PROPERTIES LABELS "cli;fit"
                     FIXTURES_REQUIRED synth_environment SKIP_RETURN_CODE 77)

# bad input: exit status 2 and a message naming what is wrong
set(NEVER ${CMAKE_CURRENT_BINARY_DIR}/never_environment)
clayfit_cli_test(error_synth_environment_missing --exit 2
  --stderr "--environment: no file '/nonexistent/sky.exr'" --
  ${CLAYFIT} synth -o ${NEVER} --environment /nonexistent/sky.exr)
clayfit_cli_test(error_synth_environment_lights --exit 2
  --stderr "--environment-lights: 65537 is outside \\[1, 65536\\]" --
  ${CLAYFIT} synth -o ${NEVER} --environment ${PROJECT_SOURCE_DIR}/README.md
  --environment-lights 65537)
clayfit_cli_test(error_synth_environment_rotation_count --exit 2
  --stderr "--environment-rotation: '1,0,0' has 3 numbers, expected 9" --
  ${CLAYFIT} synth -o ${NEVER} --environment ${PROJECT_SOURCE_DIR}/README.md
  --environment-rotation 1,0,0)
clayfit_cli_test(error_synth_environment_flash --exit 2
  --stderr "--environment replaces the flash: not with --flash-offset" --
  ${CLAYFIT} synth -o ${NEVER} --environment ${PROJECT_SOURCE_DIR}/README.md
  --flash-offset 1,0,0)
clayfit_cli_test(error_synth_environment_reference --exit 2
  --stderr "--environment replaces the flash: not with --reference" --
  ${CLAYFIT} synth -o ${NEVER} --reference 0.5 --environment ${PROJECT_SOURCE_DIR}/README.md)
clayfit_cli_test(error_synth_environment_not_an_image --exit 2
  --stderr "README.md: cannot read this image" --
  ${CLAYFIT} synth -o ${NEVER} --images 1 --size 32x32
  --environment ${PROJECT_SOURCE_DIR}/README.md)
clayfit_cli_test(error_synth_environment_rotation --exit 2 --skip-unless ${ENV_MAP}
  --stderr "rotation is not orthonormal" --
  ${CLAYFIT} synth -o ${NEVER} --images 1 --size 32x32 --environment ${ENV_MAP}
  --environment-rotation 1,0,0,0,1,0,0,0,2)
set_tests_properties(cli_error_synth_environment_rotation PROPERTIES SKIP_RETURN_CODE 77)

# A synth --environment capture against the map's exact integral (every
# map pixel a light): the measuring tool of docs/captures.md's convergence
# table, and one of its figures as a test: M2 under studio.exr at K = 4096,
# pixel centres of a 160 x 120 image, within 0.15 % (measured 0.047 %;
# K = 256 gives 2.3 %).
add_executable(envmap_exact capture/envmap_exact.c)
target_link_libraries(envmap_exact PRIVATE clayfit_capture clayfit_warnings)
target_include_directories(envmap_exact PRIVATE ${PROJECT_SOURCE_DIR}/src)
set(SYNTH_EXACT ${CMAKE_CURRENT_BINARY_DIR}/cli_synth_environment_exact)
add_test(NAME cli_synth_environment_exact_render
         COMMAND ${CHECK} --skip-unless ${ENV_MAP} --
                 ${CLAYFIT} --quiet synth -o ${SYNTH_EXACT} --environment ${ENV_MAP}
                 --environment-lights 4096 --images 1 --size 160x120 --format exr --no-noise
                 --supersample 1 --model M2 --param albedo=0.5,0.4,0.3
                 --param diffuse_roughness=0.3 --param roughness=0.3 --param f0=0.05)
set_tests_properties(cli_synth_environment_exact_render PROPERTIES LABELS "cli;capture"
                     FIXTURES_SETUP synth_environment_exact SKIP_RETURN_CODE 77)
add_test(NAME cli_synth_environment_exact
         COMMAND ${CHECK} --skip-unless ${ENV_MAP}
                 --expect "doc['relative_rmse'] < 0.0015 and doc['observations'] > 400"
                 -- $<TARGET_FILE:envmap_exact> ${SYNTH_EXACT} 10)
set_tests_properties(cli_synth_environment_exact PROPERTIES LABELS "cli;capture"
                     FIXTURES_REQUIRED synth_environment_exact SKIP_RETURN_CODE 77)
