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
