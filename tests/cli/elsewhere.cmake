# Fit in one folder, report and export from another: fit.json records its
# capture relative to its own folder (data_schema/fit.schema.json,
# capture.path), and still reads the fit.json files written before, which
# have it relative to the folder clayfit fit ran in. On the way, a fit that
# ends at a bound (M1 on a noisy M0 capture puts diffuse_roughness, the
# Oren-Nayar sigma, at 0) says so in the summary instead of "± nan".
set(ELSEWHERE ${CMAKE_CURRENT_BINARY_DIR}/cli_elsewhere)
add_test(NAME cli_elsewhere_synth
         COMMAND ${CLAYFIT} --quiet synth -o ${ELSEWHERE}/capture --model M0 --images 4
                 --size 100x75 --format exr --supersample 1)
add_test(NAME cli_elsewhere_folder COMMAND ${CMAKE_COMMAND} -E make_directory ${ELSEWHERE}/other)
set_tests_properties(cli_elsewhere_synth cli_elsewhere_folder PROPERTIES LABELS "cli;fit"
                     FIXTURES_SETUP elsewhere_capture)
clayfit_cli_test(fit_at_bound --cwd ${ELSEWHERE}
  --stdout "diffuse_roughness +0 \\(at lower bound\\)" --stdout-not "nan"
  --json-file ${ELSEWHERE}/fit/fit.json --schema ${SCHEMA}/fit.schema.json
  --expect "doc['params']['diffuse_roughness']['status'] == 'fitted: at a bound of its range'"
  --expect "doc['params']['diffuse_roughness']['sd'] is None"
  --expect "doc['capture']['path'] == '../capture/capture.json'"
  -- ${CLAYFIT} --quiet fit capture/capture.json -o fit --model M1 --footprint centre)
set_tests_properties(cli_fit_at_bound PROPERTIES LABELS "cli;fit"
                     FIXTURES_REQUIRED elsewhere_capture FIXTURES_SETUP elsewhere_fit)
# from another folder: the report finds the capture, the preset names it
clayfit_cli_test(report_elsewhere --cwd ${ELSEWHERE}/other
  --json-file ${ELSEWHERE}/other/report/report.json
  --expect "os.path.samefile(os.path.join('${ELSEWHERE}/other', doc['capture']['path']), '${ELSEWHERE}/capture/capture.json')"
  -- ${CLAYFIT} --quiet report ../fit/fit.json -o report)
clayfit_cli_test(export_elsewhere --cwd ${ELSEWHERE}/other
  --json-file ${ELSEWHERE}/other/preset.json
  --expect "os.path.isfile(os.path.join('${ELSEWHERE}/other', doc['provenance']['capture']['path']))"
  -- ${CLAYFIT} export ../fit/fit.json --format json -o preset.json)
# a fit.json as clayfit wrote it before: the capture relative to the folder
# clayfit fit ran in (here ${ELSEWHERE})
add_test(NAME cli_elsewhere_old_fit
         COMMAND ${CLAYFIT_PYTHON} -c
         "import json, os, sys; d = json.load(open(sys.argv[1])); d['capture']['path'] = 'capture/capture.json'; os.makedirs(os.path.dirname(sys.argv[2]), exist_ok=True); json.dump(d, open(sys.argv[2], 'w'), indent=2)"
         ${ELSEWHERE}/fit/fit.json ${ELSEWHERE}/old/fit.json)
set_tests_properties(cli_elsewhere_old_fit PROPERTIES FIXTURES_SETUP elsewhere_old)
clayfit_cli_test(report_old_fit --cwd ${ELSEWHERE}
  -- ${CLAYFIT} --quiet report old/fit.json -o old/report)
clayfit_cli_test(error_report_old_fit_elsewhere --cwd ${ELSEWHERE}/other --exit 2
  --stderr "capture.path 'capture/capture.json': no capture at \\.\\./old/capture/capture.json \\(relative to the folder of fit.json\\) nor at capture/capture.json \\(relative to the current folder"
  -- ${CLAYFIT} --quiet report ../old/fit.json -o never)
foreach(name report_elsewhere export_elsewhere report_old_fit error_report_old_fit_elsewhere)
  set_tests_properties(cli_${name} PROPERTIES LABELS "cli;report;export"
                       FIXTURES_REQUIRED "elsewhere_capture;elsewhere_fit")
endforeach()
set_tests_properties(cli_elsewhere_old_fit PROPERTIES LABELS "cli"
                     FIXTURES_REQUIRED "elsewhere_capture;elsewhere_fit")
set_tests_properties(cli_report_old_fit cli_error_report_old_fit_elsewhere PROPERTIES
                     FIXTURES_REQUIRED "elsewhere_capture;elsewhere_fit;elsewhere_old")
