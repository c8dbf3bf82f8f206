# Where the commands write (issue 16, items 6 and 15).
#
# A bad output location (an empty path, a file where a folder is expected or
# a folder where a file is, a path under a regular file, a missing parent
# folder of a file, /proc, a read-only folder when not root) is refused
# before any loading, fitting or rendering: exit 2, the option, the path and
# the reason (tests/cli/check_output_paths.py; one test per command).
foreach(command fit report export synth inspect lights bench-work bench-json)
  add_test(NAME cli_output_path_${command}
           COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/cli/check_output_paths.py
                   ${CLAYFIT} ${command} ${CMAKE_CURRENT_BINARY_DIR}/cli_output_paths/${command})
  set_tests_properties(cli_output_path_${command} PROPERTIES LABELS "cli")
endforeach()

# clayfit inspect writes overlays only with -o DIR; for an orthographic
# sphere_from_silhouettes capture it reports the fitted outline in pixels
# (the sphere has no world centre or radius there). A synthetic capture
# (tests/cli/make_ortho_capture.py: a disc of radius 24 px about (50, 40)),
# and the real DiLiGenT ball (skipped without ../shared/data).
set(ORTHO ${CMAKE_CURRENT_BINARY_DIR}/cli_ortho)
add_test(NAME cli_ortho_capture
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/cli/make_ortho_capture.py ${ORTHO})
set_tests_properties(cli_ortho_capture PROPERTIES LABELS "cli" FIXTURES_SETUP ortho_capture)
clayfit_cli_test(inspect_ortho_circle --schema ${SCHEMA}/inspect.schema.json
  --expect "doc['sphere']['center'] is None and doc['sphere']['radius'] is None"
  --expect "abs(doc['sphere']['circle']['radius_px'] - 24) < 1"
  --expect "math.dist(doc['sphere']['circle']['center_px'], [50, 40]) < 1"
  --expect "doc['sphere']['circle']['fitted_to'].endswith('mask.png')"
  --expect "'overlays' not in doc and not os.path.exists('${ORTHO}/inspect')"
  -- ${CLAYFIT} --quiet inspect --json ${ORTHO}/capture.json)
clayfit_cli_test(inspect_ortho_circle_text
  --stdout "outline fitted to .*mask\\.png.*: centre 50 40 px, radius 2[34]\\.[0-9]+ px"
  --stdout-not "overlays"
  -- ${CLAYFIT} --quiet inspect ${ORTHO}/capture.json)
clayfit_cli_test(inspect_ortho_overlays --schema ${SCHEMA}/inspect.schema.json
  --expect "doc['overlays'] == ['${ORTHO}/overlays/photo.png']"
  --expect "os.path.isfile('${ORTHO}/overlays/photo.png')"
  -- ${CLAYFIT} --quiet inspect --json -o ${ORTHO}/overlays ${ORTHO}/capture.json)
set_tests_properties(cli_inspect_ortho_circle cli_inspect_ortho_circle_text
                     cli_inspect_ortho_overlays PROPERTIES LABELS "cli;capture"
                     FIXTURES_REQUIRED ortho_capture)
# the overlays test writes into ${ORTHO}: the others look for no inspect/ there
set_tests_properties(cli_inspect_ortho_overlays PROPERTIES DEPENDS
                     "cli_inspect_ortho_circle;cli_inspect_ortho_circle_text")
# an image output that exists and is not a regular file (here a FIFO that no
# process reads, on which a plain write waits forever) is refused, exit 2
add_test(NAME cli_inspect_overlay_fifo
         COMMAND ${CHECK} --exit 2
                 --stderr "fifo_overlays/photo.png: exists and is not a regular file; an image is written to a file"
                 -- sh -c "rm -rf '${ORTHO}/fifo_overlays' && mkdir '${ORTHO}/fifo_overlays' && mkfifo '${ORTHO}/fifo_overlays/photo.png' && exec '${CLAYFIT}' --quiet inspect -o '${ORTHO}/fifo_overlays' '${ORTHO}/capture.json'")
set_tests_properties(cli_inspect_overlay_fifo PROPERTIES LABELS "cli;capture" TIMEOUT 120
                     FIXTURES_REQUIRED ortho_capture)
clayfit_cli_test(inspect_diligent_circle --skip-unless ${CLAYFIT_SHARED_DATA}/diligent_ball
  --schema ${SCHEMA}/inspect.schema.json
  --expect "doc['camera'] == 'orthographic' and doc['sphere']['center'] is None"
  --expect "60 < doc['sphere']['circle']['radius_px'] < 80"
  --expect "abs(doc['sphere']['circle']['semi_axes_px'][0] / doc['sphere']['circle']['semi_axes_px'][1] - 1) < 0.01"
  --expect "'overlays' not in doc"
  -- ${CLAYFIT} --quiet inspect --json ${PROJECT_SOURCE_DIR}/tests/diligent_ball_circle.capture.json)
set_tests_properties(cli_inspect_diligent_circle PROPERTIES LABELS "cli;capture"
                     SKIP_RETURN_CODE 77)
