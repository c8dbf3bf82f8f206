# clayfit batch (docs/batch.md): the manifest's errors, and a library of
# six small synthetic captures through the local executor (fitted to the
# bit as clayfit fit, a failure, re-runs, a changed capture, a killed
# worker, the lock).
add_test(NAME batch_manifest_errors
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/batch/check_manifest_errors.py
                 ${CLAYFIT} ${CMAKE_CURRENT_BINARY_DIR}/batch_manifest_errors)
set_tests_properties(batch_manifest_errors PROPERTIES LABELS "batch;cli")
add_test(NAME batch_local
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/batch/check_batch.py
                 ${CLAYFIT} ${SCHEMA} ${CMAKE_CURRENT_BINARY_DIR}/batch_local)
set_tests_properties(batch_local PROPERTIES LABELS "batch;cli")

# The library batch_local leaves (five fitted, one failed) as a fixture: its
# thumbnails, library.json and index.html agree; `clayfit library compare`
# (an entry with itself: all 0; two entries: (a-b)/sqrt(sda²+sdb²) from
# fit.json; the errors exit 2); index.html in headless Chromium with every
# thumbnail loaded (skipped without Chromium).
set_tests_properties(batch_local PROPERTIES FIXTURES_SETUP batch_library)
add_test(NAME batch_library
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/batch/check_library.py
                 ${CLAYFIT} ${SCHEMA} ${CMAKE_CURRENT_BINARY_DIR}/batch_local/library
                 ${CMAKE_CURRENT_BINARY_DIR}/batch_library)
set_tests_properties(batch_library PROPERTIES LABELS "batch;cli" FIXTURES_REQUIRED batch_library)
add_test(NAME batch_gallery_browser
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/batch/check_library.py
                 ${CLAYFIT} ${SCHEMA} ${CMAKE_CURRENT_BINARY_DIR}/batch_local/library
                 ${CMAKE_CURRENT_BINARY_DIR}/batch_gallery_browser --browser)
set_tests_properties(batch_gallery_browser PROPERTIES LABELS "batch;cli"
                     FIXTURES_REQUIRED batch_library SKIP_RETURN_CODE 77 TIMEOUT 300)
# batch_slurm: the same six captures through --executor slurm on the private
# cluster (tests/slurm/slurm.cmake's fixture): to the bit as clayfit fit and
# as the local executor, a re-run and --dry-run submit nothing, scancel of a
# running element leaves failed.json and the next run fits it.
add_test(NAME batch_slurm
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/batch/check_batch_slurm.py
                 ${CLAYFIT} ${SCHEMA} ${CMAKE_CURRENT_BINARY_DIR}/batch_slurm)
set_tests_properties(batch_slurm PROPERTIES LABELS "batch;slurm;slow" FIXTURES_REQUIRED slurm
                     RESOURCE_LOCK slurm_cluster
                     ENVIRONMENT SLURM_CONF=${CMAKE_BINARY_DIR}/slurm/slurm.conf
                     SKIP_RETURN_CODE 77 TIMEOUT 300)

# batch_hostile: -o naming a file, a lock without a pid, captures and images
# that are not regular files (never a hang), SIGINT while the captures are
# read, the main process SIGKILLed (its worker dies with it), and failures
# that are not the capture's (a file-size limit as a full disk; out of
# memory under a limit of address space, not with the sanitizers, which
# reserve terabytes of it) keeping the earlier entry whole.
if(CLAYFIT_SANITIZE)
  set(batch_memory_limit "")
else()
  set(batch_memory_limit --memory-limit)
endif()
add_test(NAME batch_hostile
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/batch/check_batch_hostile.py
                 ${CLAYFIT} ${CMAKE_CURRENT_BINARY_DIR}/batch_hostile ${batch_memory_limit})
set_tests_properties(batch_hostile PROPERTIES LABELS "batch;cli;slow" TIMEOUT 600)
