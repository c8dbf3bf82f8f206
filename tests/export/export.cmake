# Reading fit.json back, and the material presets (clayfit export).
clayfit_c_test(test_fit_read SOURCES export/test_fit_read.c LIBS clayfit_fit_test_support
               LABELS "fit;export")
# The note of a tailed lobe's GGX in the GGX-only formats (the GGX itself:
# test_tailed_ggx, tests/CMakeLists.txt).
clayfit_c_test(test_tailed_note SOURCES export/test_tailed_note.c LIBS clayfit_export
               LABELS export)

# One fit.json per model (tests/export/make_fits.py: schema-valid, written
# without fitting), each exported to every format and the file validated by
# an independent tool (tests/export/check_export.py): the json preset
# against data_schema/preset.schema.json and evaluated back (clayfit eval
# --preset equals the fit's parameters to the last bit), MaterialX and
# Mitsuba by xmllint and the standard definitions' names, glTF by the
# Khronos validator (npm gltf-validator), the Blender script by py_compile.
# A missing tool skips (exit 77).
set(EXPORT_DIR ${CMAKE_CURRENT_BINARY_DIR}/export)
set(EXPORT_CHECK ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/export/check_export.py)
set(EXPORT_NODE_MODULES ${PROJECT_SOURCE_DIR}/build/tools/node_modules)
add_test(NAME cli_export_fixtures
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/export/make_fits.py ${CLAYFIT}
                 ${EXPORT_DIR})
set_tests_properties(cli_export_fixtures PROPERTIES LABELS "cli;export" FIXTURES_SETUP export_fits)
add_test(NAME cli_export_fixtures_valid
         COMMAND ${CLAYFIT_PYTHON} -c
         "import json, sys, jsonschema; s = json.load(open(sys.argv[1])); [jsonschema.Draft202012Validator(s).validate(json.load(open(f'{sys.argv[2]}/{m}/fit.json'))) for m in ('M0', 'M1', 'M2', 'M3', 'M4', 'M2T', 'M4T', 'M2T-tail2')]"
         ${SCHEMA}/fit.schema.json ${EXPORT_DIR})
set_tests_properties(cli_export_fixtures_valid PROPERTIES LABELS "cli;export"
                     FIXTURES_REQUIRED export_fits)
# The tailed rungs M2T and M4T too (docs/presets.md, "Tailed lobes in
# GGX-only formats"): their json preset keeps the tail and evaluates back to
# the bit; every other format carries one "GGX approximation: N % RMS over the
# lobe" note per tailed lobe (and the GGX-only models none). M2T-tail2 (tail 2)
# writes the values of M2's export and an exact note with 0 %.
foreach(model M0 M1 M2 M3 M4 M2T M4T M2T-tail2)
  foreach(format json mtlx mtlx-openpbr gltf blender mitsuba)
    set(twin)
    if(model STREQUAL "M2T-tail2" AND NOT format STREQUAL "json")
      set(twin --same-values-as ${EXPORT_DIR}/M2/fit.json)
    endif()
    add_test(NAME cli_export_${model}_${format}
             COMMAND ${EXPORT_CHECK} ${CLAYFIT} ${EXPORT_DIR}/${model}/fit.json ${format}
                     ${EXPORT_DIR}/${model}/preset.${format} --schema ${SCHEMA}
                     --node-modules ${EXPORT_NODE_MODULES} ${twin})
    set_tests_properties(cli_export_${model}_${format} PROPERTIES LABELS "cli;export"
                         FIXTURES_REQUIRED export_fits SKIP_RETURN_CODE 77)
  endforeach()
endforeach()
# A real fit (clayfit fit's own fit.json of the small M2 capture): its json
# preset evaluates as the fit.
add_test(NAME cli_export_real_fit_json
         COMMAND ${EXPORT_CHECK} ${CLAYFIT} ${FIT_SMALL}/hold/fit.json json
                 ${FIT_SMALL}/hold/preset.json --schema ${SCHEMA})
set_tests_properties(cli_fit_forced_hold PROPERTIES FIXTURES_SETUP fit_small_hold)
set_tests_properties(cli_export_real_fit_json PROPERTIES LABELS "cli;export;fit"
                     FIXTURES_REQUIRED "fit_small;fit_small_hold")
# The warning of a value a target cannot take (M4's oil film, F0 0.06,
# above the principled clear coat's F0 0.04 in Mitsuba; glTF writes the film
# as its specular lobe since docs/fidelity.md's three.js rows).
clayfit_cli_test(export_range_warning --stderr "warning: mitsuba: clearcoat = film_f0 / 0.04 = 1.5 is above 1: written as 1"
  -- ${CLAYFIT} export ${EXPORT_DIR}/M4/fit.json --format mitsuba -o ${EXPORT_DIR}/M4/warned.xml)
include(${CMAKE_CURRENT_LIST_DIR}/gltf_threejs.cmake)
set_tests_properties(cli_export_range_warning PROPERTIES LABELS "cli;export" FIXTURES_REQUIRED export_fits)
# bad input: exit 2 with the reason
clayfit_cli_test(error_export_missing_fit --exit 2 --stderr "no-such-fit.json"
  -- ${CLAYFIT} export ${EXPORT_DIR}/no-such-fit.json --format json -o ${EXPORT_DIR}/never.json)
clayfit_cli_test(error_export_wrong_type --exit 2
  --stderr "bad/fit.json: params.roughness.value: expected a number, got a string"
  -- ${CLAYFIT} export ${EXPORT_DIR}/bad/fit.json --format gltf -o ${EXPORT_DIR}/never.gltf)
clayfit_cli_test(error_export_unknown_format --exit 2
  --stderr "unknown format 'obj' \\(the formats are json, mtlx, mtlx-openpbr, gltf, blender, mitsuba, glsl, unity\\)"
  -- ${CLAYFIT} export ${EXPORT_DIR}/M2/fit.json --format obj -o ${EXPORT_DIR}/never.obj)
clayfit_cli_test(error_export_no_format --exit 2 --stderr "expected FIT.json --format F -o PATH"
  -- ${CLAYFIT} export ${EXPORT_DIR}/M2/fit.json -o ${EXPORT_DIR}/never.json)
clayfit_cli_test(error_eval_bad_preset --exit 2
  --stderr "M2/fit.json: \\(top level\\): unknown key .clayfit_fit."
  -- ${CLAYFIT} eval --preset ${EXPORT_DIR}/M2/fit.json ${UP})
# Model versions (docs/model.md, top): a fit.json of version 1 (no
# model_version key: Schlick's Fresnel) is still exported, with one warning;
# an unknown version is refused, naming the file and the field.
clayfit_cli_test(export_model_version_1
  --stderr "M2-v1/fit.json: the values were fitted with model version 1 \\(Schlick's Fresnel\\)"
  -- ${CLAYFIT} export ${EXPORT_DIR}/M2-v1/fit.json --format json -o ${EXPORT_DIR}/M2-v1/preset.json)
clayfit_cli_test(error_export_model_version --exit 2
  --stderr "M2-v3/fit.json: model_version: unknown model version 3"
  -- ${CLAYFIT} export ${EXPORT_DIR}/M2-v3/fit.json --format json -o ${EXPORT_DIR}/never.json)
foreach(name error_export_missing_fit error_export_wrong_type error_export_unknown_format
        error_export_no_format error_eval_bad_preset export_model_version_1
        error_export_model_version)
  set_tests_properties(cli_${name} PROPERTIES LABELS "cli;export" FIXTURES_REQUIRED export_fits)
endforeach()

# Hostile names (issue 16): the capture's name and path in fit.json and the
# fit file's folder hold code after newlines, `-->`, markup, quotes, `"""`,
# backslashes, control characters and invalid UTF-8; every format is exported
# and checked (tests/export/check_export_hostile.py): the Blender script's AST
# is the clean export's and runs nothing injected, the XML parses with one
# comment that gives the name back, the JSON holds it; a NUL is refused.
add_test(NAME cli_export_hostile_names
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/export/check_export_hostile.py
                 ${CLAYFIT} ${EXPORT_DIR}/M4/fit.json ${CMAKE_CURRENT_BINARY_DIR}/export_hostile)
set_tests_properties(cli_export_hostile_names PROPERTIES LABELS "cli;export"
                     FIXTURES_REQUIRED export_fits)
include(${CMAKE_CURRENT_LIST_DIR}/blender.cmake)
include(${CMAKE_CURRENT_LIST_DIR}/shader.cmake)
