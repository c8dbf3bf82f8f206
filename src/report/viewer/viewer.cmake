# The report's interactive view of the material (docs/report.md, "The
# material, interactive"): three.js from npm (scripts/install-deps.sh puts
# three and esbuild into build/tools/node_modules) and viewer.js, bundled by
# esbuild into one classic script beside clayfit, clayfit-report-viewer.js,
# which `clayfit report` copies into every report (Chromium runs no ES module
# from file://). Nothing of three.js is in the repository. Without three or
# esbuild it is not built, and the reports say that their view is absent.
set(CLAYFIT_NODE_MODULES ${PROJECT_SOURCE_DIR}/build/tools/node_modules CACHE PATH
    "npm packages (three, esbuild) for the report's three.js bundle")
set(CLAYFIT_REPORT_VIEWER ${PROJECT_BINARY_DIR}/src/cli/clayfit-report-viewer.js)
if(EXISTS ${CLAYFIT_NODE_MODULES}/three/package.json AND EXISTS ${CLAYFIT_NODE_MODULES}/.bin/esbuild)
  add_custom_command(
    OUTPUT ${CLAYFIT_REPORT_VIEWER}
    COMMAND ${CMAKE_COMMAND} -E env NODE_PATH=${CLAYFIT_NODE_MODULES}
            ${CLAYFIT_NODE_MODULES}/.bin/esbuild ${CMAKE_CURRENT_LIST_DIR}/viewer.js --bundle
            --format=iife --minify --log-level=warning --outfile=${CLAYFIT_REPORT_VIEWER}
    DEPENDS ${CMAKE_CURRENT_LIST_DIR}/viewer.js ${CLAYFIT_NODE_MODULES}/three/package.json
    COMMENT "Bundling three.js for the report's material view"
    VERBATIM)
  add_custom_target(clayfit_report_viewer ALL DEPENDS ${CLAYFIT_REPORT_VIEWER})
else()
  message(STATUS "No three or esbuild in ${CLAYFIT_NODE_MODULES}: the report's interactive "
                 "view is not built (run scripts/install-deps.sh, then configure again)")
endif()
