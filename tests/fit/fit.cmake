# Tests of the fit.
add_library(clayfit_fit_test_support STATIC fit/fit_support.c)
target_link_libraries(clayfit_fit_test_support PUBLIC clayfit_fit clayfit_capture clayfit_test_support
                      PRIVATE clayfit_warnings m)
clayfit_c_test(test_fit_recovery SOURCES fit/test_fit_recovery.c LIBS clayfit_fit_test_support LABELS fit)
clayfit_c_test(test_fit_choice SOURCES fit/test_fit_choice.c LIBS clayfit_fit_test_support
               LABELS "fit;slow")

# clayfit fit on a small noise-free EXR capture of M2: fit.json valid
# against its schema, the truth recovered, the model choice recorded.
set(FIT_SMALL ${CMAKE_CURRENT_BINARY_DIR}/cli_fit_small)
add_test(NAME cli_fit_synth COMMAND ${CLAYFIT} --quiet synth -o ${FIT_SMALL} --model M2
         --images 8 --size 200x150 --format exr --no-noise --supersample 1
         --param albedo=0.6,0.4,0.3 --param roughness=0.3 --param f0=0.05
         --param diffuse_roughness=0.3)
set_tests_properties(cli_fit_synth PROPERTIES LABELS "cli;fit" FIXTURES_SETUP fit_small)
function(clayfit_fit_cli_test name)
  clayfit_cli_test(${name} ${ARGN})
  set_tests_properties(cli_${name} PROPERTIES LABELS "cli;fit" FIXTURES_REQUIRED fit_small)
endfunction()
clayfit_fit_cli_test(fit_auto --schema ${SCHEMA}/fit.schema.json
  --json-file ${FIT_SMALL}/auto/fit.json
  --expect "doc['model']['code'] == 'M2' and doc['choice']['mode'] == 'auto'"
  --expect "[c['model'] for c in doc['choice']['candidates']] == ['M0', 'M1', 'M2', 'M3', 'M4']"
  --expect "sum(c['chosen'] for c in doc['choice']['candidates']) == 1"
  --expect "abs(doc['params']['roughness']['value'] - 0.3) < 1e-4"
  --expect "abs(doc['params']['f0']['value'] - 0.05) < 1e-4"
  --expect "doc['residuals']['relative_rmse'] < 1e-4"
  --expect "len(doc['residuals']['per_image']) == 8"
  --expect "doc['timing']['choice_s'] > 0"
  --expect "doc['footprint']['mode'] == 'centre' and doc['footprint']['observations'] == 0"
  --expect "doc['response'] == {'value': 1.0, 'sd': 0.0, 'fitted': False, 'meaning': doc['response']['meaning']}"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/capture.json -o ${FIT_SMALL}/auto --footprint centre)
clayfit_fit_cli_test(fit_forced_hold --schema ${SCHEMA}/fit.schema.json
  --json-file ${FIT_SMALL}/hold/fit.json
  --expect "doc['model']['code'] == 'M2' and doc['choice'] == {'mode': 'forced', 'chosen': 'M2', 'candidates': []}"
  --expect "doc['params']['f0']['value'] == 0.05 and doc['params']['f0']['status'] == 'held'"
  --expect "doc['held'] == [{'name': 'f0', 'value': 0.05, 'why': 'held'}]"
  --expect "doc['params']['f0']['sd'] == 0"
  --expect "abs(doc['params']['roughness']['value'] - 0.3) < 1e-4"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/capture.json -o ${FIT_SMALL}/hold --model dielectric
     --hold f0=0.05 --loss none --footprint centre)
# A pixel budget: the sample recorded, the residuals estimated for every
# observation; a solve out of iterations says so.
clayfit_fit_cli_test(fit_budget --schema ${SCHEMA}/fit.schema.json
  --json-file ${FIT_SMALL}/budget/fit.json
  --expect "doc['sample']['sampling'] == 'importance' and doc['sample']['observations'] <= 3002"
  --expect "doc['sample']['population'] > 10 * doc['sample']['observations']"
  --expect "abs(doc['params']['roughness']['value'] - 0.3) < 1e-4"
  --expect "doc['residuals']['count'] <= 3 * 3002 and doc['residuals']['relative_rmse'] < 1e-4"
  --expect "not any('without converging' in w for w in doc['warnings'])"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/capture.json -o ${FIT_SMALL}/budget --model M2
     --footprint centre --budget 3000 --sampling importance)
clayfit_fit_cli_test(fit_out_of_iterations --schema ${SCHEMA}/fit.schema.json
  --json-file ${FIT_SMALL}/short/fit.json
  --expect "doc['solver']['termination'] == 'NO_CONVERGENCE'"
  --expect "any('without converging' in w and '--max-iterations' in w for w in doc['warnings'])"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/capture.json -o ${FIT_SMALL}/short --model M2
     --footprint centre --max-iterations 1 --no-multistart)
# An unknown tone curve: the same capture's linear EXR values decoded as
# stored^1.5 (encoding "gamma", gamma 1.5) with tone_curve "unknown": the
# fitted response exponent is 1.5 and the material unchanged.
add_test(NAME cli_fit_gamma_capture
         COMMAND ${CLAYFIT_PYTHON} -c
         "import json, sys; d = json.load(open(sys.argv[1])); d['colour'] = {'encoding': 'gamma', 'gamma': 1.5, 'tone_curve': 'unknown'}; json.dump(d, open(sys.argv[2], 'w'), indent=2)"
         ${FIT_SMALL}/capture.json ${FIT_SMALL}/gamma.json)
set_tests_properties(cli_fit_gamma_capture PROPERTIES LABELS "cli;fit" FIXTURES_REQUIRED fit_small
                     FIXTURES_SETUP fit_gamma)
clayfit_fit_cli_test(fit_response --schema ${SCHEMA}/fit.schema.json
  --json-file ${FIT_SMALL}/gamma/fit.json
  --expect "doc['response']['fitted'] and abs(doc['response']['value'] - 1.5) < 1e-4"
  --expect "0 < doc['response']['sd'] < 0.01"
  --expect "abs(doc['params']['roughness']['value'] - 0.3) < 1e-4"
  --expect "abs(doc['params']['f0']['value'] - 0.05) < 1e-4"
  --expect "max(abs(a - b) for a, b in zip(doc['params']['albedo']['value'], [0.6, 0.4, 0.3])) < 1e-4"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/gamma.json -o ${FIT_SMALL}/gamma --model M2 --footprint centre)
set_tests_properties(cli_fit_response PROPERTIES FIXTURES_REQUIRED "fit_small;fit_gamma")
# errors: exit 2 with the reason on stderr, no fit.json
clayfit_fit_cli_test(error_fit_hold_out_of_range --exit 2 --stderr "--hold f0=0.5 is outside its range \\[0, 0.25\\]"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/capture.json -o ${FIT_SMALL}/never --model M2 --hold f0=0.5)
clayfit_fit_cli_test(error_fit_hold_unknown --exit 2 --stderr "--hold shininess: no model of the ladder has a parameter"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/capture.json -o ${FIT_SMALL}/never --hold shininess=3)
clayfit_fit_cli_test(error_fit_hold_not_in_model --exit 2 --stderr "model M2 \\(dielectric\\) has no parameter 'film_f0'"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/capture.json -o ${FIT_SMALL}/never --model M2 --hold film_f0=0.02)
clayfit_fit_cli_test(error_fit_free_unknown --exit 2 --stderr "--free gloss: no model of the ladder"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/capture.json -o ${FIT_SMALL}/never --free gloss)
clayfit_fit_cli_test(error_fit_bad_loss --exit 2 --stderr "--loss: 'l1' is not huber, cauchy or none"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/capture.json -o ${FIT_SMALL}/never --loss l1)
clayfit_fit_cli_test(error_fit_bad_footprint --exit 2 --stderr "--footprint: 'fine' is not auto, centre or a number"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/capture.json -o ${FIT_SMALL}/never --footprint fine)
clayfit_fit_cli_test(error_fit_footprint_too_many --exit 2 --stderr "--footprint: '17' is not auto, centre or a number of samples per side from 1 to 16"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/capture.json -o ${FIT_SMALL}/never --footprint 17)
clayfit_fit_cli_test(error_fit_footprint_tolerance --exit 2 --stderr "--footprint-tolerance must be in \\(0, 1\\)"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/capture.json -o ${FIT_SMALL}/never --footprint-tolerance 0)
clayfit_fit_cli_test(error_fit_bad_model --exit 2 --stderr "M9"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/capture.json -o ${FIT_SMALL}/never --model M9)
clayfit_fit_cli_test(error_fit_hold_nan --exit 2 --stderr "--hold roughness"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/capture.json -o ${FIT_SMALL}/never --hold roughness=nan)
clayfit_cli_test(error_fit_no_capture --exit 2 --stderr "no-such-capture.json"
  -- ${CLAYFIT} --quiet fit ${FIT_SMALL}/no-such-capture.json -o ${FIT_SMALL}/never)
# statistics over many fits: slow under the sanitizers, which the recovery
# and hard-case tests already take through the same code
clayfit_c_test(test_fit_calibration SOURCES fit/test_fit_calibration.c LIBS clayfit_fit_test_support
               LABELS "fit;slow")
# the same with a pixel budget (about a tenth of the observations): the
# standard deviations of a weighted sample
foreach(sampling uniform stratified importance)
  add_test(NAME test_fit_calibration_budget_${sampling}
           COMMAND test_fit_calibration 3000 ${sampling})
  set_tests_properties(test_fit_calibration_budget_${sampling} PROPERTIES LABELS "fit;slow"
                       SKIP_RETURN_CODE 77)
endforeach()
# Pixel footprints: a highlight narrower than a pixel, rendered with 4 x 4
# and 16 x 16 samples per pixel.
clayfit_c_test(test_fit_footprint SOURCES fit/test_fit_footprint.c LIBS clayfit_fit_test_support
               LABELS fit)
# the multi-start's ambiguity test, a private function of src/fit
clayfit_c_test(test_fit_ambiguous SOURCES fit/test_fit_ambiguous.c LIBS clayfit_fit LABELS fit)
target_include_directories(test_fit_ambiguous PRIVATE ${PROJECT_SOURCE_DIR}/src/fit)
clayfit_c_test(test_fit_hard_cases SOURCES fit/test_fit_hard_cases.c LIBS clayfit_fit_test_support
               LABELS fit)
# The real DiLiGenT ball (skipped without ../shared/data): about a minute.
clayfit_c_test(test_fit_diligent SOURCES fit/test_fit_diligent.c LIBS clayfit_fit clayfit_core
               LABELS "fit;slow" ARGS ${CMAKE_CURRENT_SOURCE_DIR} ${CLAYFIT_SHARED_DATA})
clayfit_c_test(test_lsq_newton_start SOURCES fit/test_lsq_newton_start.c LIBS clayfit_fit LABELS fit)
target_include_directories(test_lsq_newton_start PRIVATE ${PROJECT_SOURCE_DIR}/src/fit)
clayfit_c_test(test_lsq_extrapolate SOURCES fit/test_lsq_extrapolate.c LIBS clayfit_fit LABELS fit)
target_include_directories(test_lsq_extrapolate PRIVATE ${PROJECT_SOURCE_DIR}/src/fit)
# The fit's problem (private to src/fit): any number of unknowns, a block's
# evaluation the same on many threads at once, its cost that of the
# predictions, the slot lookup (cf_model_slot_param).
clayfit_c_test(test_fit_problem SOURCES fit/test_fit_problem.c LIBS clayfit_fit_test_support
               LABELS fit)
target_include_directories(test_fit_problem PRIVATE ${PROJECT_SOURCE_DIR}/src/fit)
# More images than the fit's unknowns once had room for (1036), exposures
# fitted: M0 rendered without noise, so every exposure is 1 and the albedo
# 0.5 (the fit crashed or returned garbage; issue 15). About 15 s.
set(FIT_MANY ${CMAKE_CURRENT_BINARY_DIR}/cli_fit_many_images)
add_test(NAME cli_fit_many_images_synth COMMAND ${CLAYFIT} --quiet synth -o ${FIT_MANY}
         --model M0 --no-noise --images 1040 --size 48x36 --supersample 1)
set_tests_properties(cli_fit_many_images_synth PROPERTIES LABELS "cli;fit;slow"
                     FIXTURES_SETUP fit_many_images)
clayfit_cli_test(fit_many_images_exposures --schema ${SCHEMA}/fit.schema.json
  --json-file ${FIT_MANY}/fit/fit.json
  --expect "doc['solver']['termination'] == 'CONVERGENCE'"
  --expect "len(doc['residuals']['per_image']) == 1040"
  --expect "all(abs(i['exposure'] - 1) < 3e-3 for i in doc['residuals']['per_image'])"
  --expect "abs(sum(math.log(i['exposure']) for i in doc['residuals']['per_image'])) < 1e-9"
  --expect "all(abs(a - 0.5) < 2e-3 for a in doc['params']['albedo']['value'])"
  -- ${CLAYFIT} --quiet fit ${FIT_MANY}/capture.json -o ${FIT_MANY}/fit --model M0 --fit-exposures
     --no-multistart)
set_tests_properties(cli_fit_many_images_exposures PROPERTIES LABELS "cli;fit;slow"
                     FIXTURES_REQUIRED fit_many_images)
