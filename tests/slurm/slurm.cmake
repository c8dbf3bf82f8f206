# A private single-node Slurm cluster (scripts/slurm-local.sh, docs/slurm.md)
# brought up once for the tests that submit jobs (FIXTURES_REQUIRED slurm,
# with SLURM_CONF=${CLAYFIT_SLURM_STATE}/slurm.conf) and down at the end.
# Label slow: only the Release pass runs them. Without slurm-wlm and munge
# every one of them skips (77).
set(CLAYFIT_SLURM_STATE ${CMAKE_BINARY_DIR}/slurm)
set(SLURM_LOCAL ${PROJECT_SOURCE_DIR}/scripts/slurm-local.sh)
add_test(NAME slurm_start COMMAND bash ${SLURM_LOCAL} start ${CLAYFIT_SLURM_STATE})
add_test(NAME slurm_stop COMMAND bash ${SLURM_LOCAL} stop ${CLAYFIT_SLURM_STATE})
set_tests_properties(slurm_start PROPERTIES FIXTURES_SETUP slurm)
set_tests_properties(slurm_stop PROPERTIES FIXTURES_CLEANUP slurm)

# slurm_array: sbatch --wait of a 4-task array, 2 at a time: each index runs
# once, exit status 0; with %1 never 2 tasks at once; a failing task's code
# comes back through sbatch --wait and squeue says FAILED.
# slurm_scancel: scancel of one running array element kills its process and
# leaves the other element running.
foreach(check array scancel)
  add_test(NAME slurm_${check}
           COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/slurm/check_${check}.sh
                   ${CLAYFIT_SLURM_STATE} ${CMAKE_CURRENT_BINARY_DIR}/slurm_${check})
  # one test at a time on the 2-CPU cluster: slurm_scancel needs both of its
  # elements running at once, which another test's tasks can prevent
  set_tests_properties(slurm_${check} PROPERTIES FIXTURES_REQUIRED slurm
                       RESOURCE_LOCK slurm_cluster)
endforeach()
set_tests_properties(slurm_start slurm_stop slurm_array slurm_scancel PROPERTIES
                     LABELS "slurm;slow" SKIP_RETURN_CODE 77 TIMEOUT 180)
