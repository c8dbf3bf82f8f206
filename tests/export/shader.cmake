# The exact model as shaders (clayfit export --format glsl / unity,
# docs/shaders.md). Both need the export fixtures (export.cmake).
#
# Every rung's three.js module and Unity shader compiled by glslangValidator
# (GLSL ES 3.0; HLSL with stubs of Unity's include files), the shared body
# the same text in both, the Unity folder's GUIDs consistent and
# deterministic, a hostile capture name kept in the comments
# (tests/export/check_shader_compile.py; skips without glslang-tools).
set(SHADER_FITS)
foreach(model M0 M1 M2 M3 M4 M2T M4T)
  list(APPEND SHADER_FITS ${EXPORT_DIR}/${model}/fit.json)
endforeach()
add_test(NAME cli_export_shader_compile
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/export/check_shader_compile.py
                 ${CLAYFIT} ${CMAKE_CURRENT_BINARY_DIR}/export_shader_compile ${SHADER_FITS})
set_tests_properties(cli_export_shader_compile PROPERTIES LABELS "cli;export"
                     FIXTURES_REQUIRED export_fits SKIP_RETURN_CODE 77)
# The three.js module rendered in headless Chromium (SwiftShader) against
# clayfit synth's rendering of the same sphere, camera and flash: relative
# RMSE <= 1e-3 for M0-M4, and two deliberately wrong M4 terms caught
# (tests/export/check_shader_threejs.py; skips without Chromium, or three
# and esbuild in build/tools/node_modules).
add_test(NAME cli_export_glsl_threejs
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/export/check_shader_threejs.py
                 ${CLAYFIT} ${EXPORT_NODE_MODULES} ${EXPORT_DIR}
                 ${CMAKE_CURRENT_BINARY_DIR}/export_glsl_threejs)
set_tests_properties(cli_export_glsl_threejs PROPERTIES LABELS "cli;export"
                     FIXTURES_REQUIRED export_fits SKIP_RETURN_CODE 77 TIMEOUT 300)
