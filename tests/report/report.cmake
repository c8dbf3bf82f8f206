# clayfit report (issue 5): the page, report.json, every picture and plot,
# and the page in a real browser.

# on the small synthetic M2 fit of fit.cmake (cli_fit_auto's fit.json)
set_tests_properties(cli_fit_auto PROPERTIES FIXTURES_SETUP fit_small_auto)
add_test(NAME cli_report_synth
         COMMAND ${CLAYFIT} --quiet report ${FIT_SMALL}/auto/fit.json -o ${FIT_SMALL}/report)
set_tests_properties(cli_report_synth PROPERTIES LABELS "cli;report"
                     FIXTURES_REQUIRED "fit_small;fit_small_auto" FIXTURES_SETUP report_synth)
add_test(NAME report_synth_files
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/report/check_report.py
                 ${FIT_SMALL}/report ${SCHEMA}/report.schema.json 8)
set_tests_properties(report_synth_files PROPERTIES LABELS "report" FIXTURES_REQUIRED report_synth)
add_test(NAME report_synth_browser
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/report/check_report_browser.py
                 ${FIT_SMALL}/report ${FIT_SMALL}/report_screenshot.png)
set_tests_properties(report_synth_browser PROPERTIES LABELS "report" FIXTURES_REQUIRED report_synth
                     SKIP_RETURN_CODE 77 TIMEOUT 400)
# Issue 19 item 4: the material's interactive view (three.js, the exact glsl
# material) draws the sphere in WebGL (SwiftShader) and matches clayfit's
# rendering; two broken materials are caught (skips without Chromium or the
# three.js bundle). Without the bundle beside clayfit, the page says so.
add_test(NAME report_synth_viewer
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/report/check_report_viewer.py
                 ${CLAYFIT} ${FIT_SMALL}/report ${CMAKE_CURRENT_BINARY_DIR}/report_viewer)
set_tests_properties(report_synth_viewer PROPERTIES LABELS "report" FIXTURES_REQUIRED report_synth
                     SKIP_RETURN_CODE 77 TIMEOUT 400)
add_test(NAME report_viewer_absent
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/report/check_report_viewer.py
                 --absent ${CLAYFIT} ${FIT_SMALL}/auto/fit.json
                 ${CMAKE_CURRENT_BINARY_DIR}/report_viewer_absent)
set_tests_properties(report_viewer_absent PROPERTIES LABELS "cli;report"
                     FIXTURES_REQUIRED "fit_small;fit_small_auto")

# errors: exit 2 with the reason
clayfit_cli_test(error_report_no_fit --exit 2 --stderr "no-such-fit.json"
  -- ${CLAYFIT} --quiet report ${FIT_SMALL}/no-such-fit.json -o ${FIT_SMALL}/never)
clayfit_cli_test(error_report_no_output --exit 2 --stderr "expected one fit.json and -o DIR"
  -- ${CLAYFIT} --quiet report ${FIT_SMALL}/auto/fit.json)
set(REPORT_OTHER ${CMAKE_CURRENT_BINARY_DIR}/report_other_capture)
add_test(NAME cli_report_other_synth COMMAND ${CLAYFIT} --quiet synth -o ${REPORT_OTHER} --model M0
         --images 4 --size 100x75 --format exr --no-noise --supersample 1)
set_tests_properties(cli_report_other_synth PROPERTIES LABELS "cli;report"
                     FIXTURES_SETUP report_other)
clayfit_cli_test(error_report_other_capture --exit 2
  --stderr "the fit has 8 images and the capture 4"
  -- ${CLAYFIT} --quiet report ${FIT_SMALL}/auto/fit.json -o ${FIT_SMALL}/never
     --capture ${REPORT_OTHER}/capture.json)
set_tests_properties(cli_error_report_no_fit cli_error_report_no_output
                     cli_error_report_other_capture PROPERTIES LABELS "cli;report")
set_tests_properties(cli_error_report_other_capture PROPERTIES
                     FIXTURES_REQUIRED "fit_small;fit_small_auto;report_other")

# The real DiLiGenT ball (skipped without ../shared/data): an M2 fit at
# pixel centres and its report of 96 images.
add_test(NAME report_diligent
         COMMAND ${CMAKE_COMMAND} -E env CLAYFIT=${CLAYFIT} PYTHON=${CLAYFIT_PYTHON}
                 bash ${CMAKE_CURRENT_SOURCE_DIR}/report/report_diligent.sh
                 ${PROJECT_SOURCE_DIR} ${CLAYFIT_SHARED_DATA} ${CMAKE_CURRENT_BINARY_DIR}/report_diligent
                 ${SCHEMA}/report.schema.json)
set_tests_properties(report_diligent PROPERTIES LABELS "report;slow" SKIP_RETURN_CODE 77 TIMEOUT 900)

# Issue 16: the report written whole or not at all (item 5), fit.json read
# once under its cap (item 13), --capture compared by its lights and colours
# (item 10). A second fit of the small capture (M0), whose report differs
# from the M2 fit's in every picture.
set(REPORT_SAFETY ${CMAKE_CURRENT_BINARY_DIR}/report_safety)
add_test(NAME cli_report_fit_m0
         COMMAND ${CLAYFIT} --quiet fit ${FIT_SMALL}/capture.json -o ${REPORT_SAFETY}/m0 --model M0
                 --footprint centre)
set_tests_properties(cli_report_fit_m0 PROPERTIES LABELS "cli;report" FIXTURES_REQUIRED fit_small
                     FIXTURES_SETUP report_fit_m0)
clayfit_c_test(test_report_atomic SOURCES report/test_report_atomic.c
               LIBS clayfit_report clayfit_core LABELS report
               ARGS ${FIT_SMALL}/capture.json ${FIT_SMALL}/auto/fit.json ${REPORT_SAFETY}/m0/fit.json
                    ${REPORT_SAFETY}/atomic)
set_tests_properties(test_report_atomic PROPERTIES
                     FIXTURES_REQUIRED "fit_small;fit_small_auto;report_fit_m0")

# Hostile names (issue 16): a synthetic capture whose name, folder and image
# names (a binary COLMAP model) hold `</script><script>`, quotes, `-->`,
# newlines and controls, fitted and reported (tests/report/check_report_hostile.py):
# the page has only its own <script> and tags, shows every name as text, the
# SVG plots parse; a \u0000 in the capture's or the fit's name is refused.
add_test(NAME report_hostile_names
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/report/check_report_hostile.py
                 ${CLAYFIT} ${CMAKE_CURRENT_BINARY_DIR}/report_hostile)
set_tests_properties(report_hostile_names PROPERTIES LABELS "cli;report")
foreach(case oversized capture folders)
  add_test(NAME report_safety_${case}
           COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/report/report_safety.py ${case}
                   ${CLAYFIT} ${FIT_SMALL} ${REPORT_SAFETY}/${case} ${SCHEMA}/report.schema.json)
  set_tests_properties(report_safety_${case} PROPERTIES LABELS "cli;report"
                       FIXTURES_REQUIRED "fit_small;fit_small_auto;report_fit_m0")
  if(CLAYFIT_SANITIZE) # no address-space limits: AddressSanitizer's shadow needs the space
    set_property(TEST report_safety_${case} APPEND PROPERTY ENVIRONMENT CLAYFIT_SANITIZE=1)
  endif()
endforeach()

# Issue 31: the pictures' 8-bit sRGB codes read from the encoding's steps,
# the same as cf_linear_to_srgb's through the PNG writer.
clayfit_c_test(test_report_srgb SOURCES report/test_report_srgb.c
               LIBS clayfit_report clayfit_core LABELS report
               ARGS ${CMAKE_CURRENT_BINARY_DIR}/report_srgb)
target_include_directories(test_report_srgb PRIVATE ${PROJECT_SOURCE_DIR}/src/report)

# Issue 20, the material library's gallery: the thumbnail (the fitted sphere
# under the standard light: the analytic Lambert value, the background, the
# PNG, every model finite, albedo order; its time printed) and the gallery
# page (hostile names and tags, every thumbnail, the controls; in headless
# Chromium every thumbnail loads and the sort and filters reorder and hide).
clayfit_c_test(test_thumbnail SOURCES report/test_thumbnail.c
               LIBS clayfit_report clayfit_core LABELS report
               ARGS ${CMAKE_CURRENT_BINARY_DIR}/thumbnail)
set(GALLERY_DIR ${CMAKE_CURRENT_BINARY_DIR}/gallery)
clayfit_c_test(test_gallery SOURCES report/test_gallery.c
               LIBS clayfit_report clayfit_core LABELS report ARGS ${GALLERY_DIR})
set_tests_properties(test_gallery PROPERTIES FIXTURES_SETUP gallery_page)
add_test(NAME gallery_page_check
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/report/check_gallery.py ${GALLERY_DIR})
set_tests_properties(gallery_page_check PROPERTIES LABELS "report" FIXTURES_REQUIRED gallery_page)
add_test(NAME gallery_browser
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/report/check_gallery.py ${GALLERY_DIR}
                 --browser ${GALLERY_DIR}/screenshot.png)
set_tests_properties(gallery_browser PROPERTIES LABELS "report" FIXTURES_REQUIRED gallery_page
                     SKIP_RETURN_CODE 77 TIMEOUT 300)

# Issue 18 item 5: the share of the rejected observations in one connected
# region per image, a systematic misfit (a glossy capture fitted with M0)
# against scattered rejections (noise beyond a loss scale of 2 sigma).
add_test(NAME report_regions
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/report/check_regions.py ${CLAYFIT}
                 ${CMAKE_CURRENT_BINARY_DIR}/report_regions)
set_tests_properties(report_regions PROPERTIES LABELS "cli;report")
