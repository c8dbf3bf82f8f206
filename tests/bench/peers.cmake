# clayfit-peers (issue 6) on a tiny capture: correctness only, never time.
# Each peer's model must agree with the C evaluator at the start (the
# executable exits 1 otherwise) and, with --check, each peer's final cost
# must be within 1e-6 relative of clayfit's (or lower). SciPy's test is
# skipped (77) when python3-scipy is missing.
set(PEERS_CAPTURE ${CMAKE_CURRENT_BINARY_DIR}/bench_peers_m2)
add_test(NAME bench_peers_synth COMMAND ${CLAYFIT} --quiet synth -o ${PEERS_CAPTURE} --model M2
         --images 2 --size 80x60 --format exr --supersample 1 --param albedo=0.7,0.5,0.3
         --param diffuse_roughness=0.5 --param roughness=0.3 --param f0=0.05)
set_tests_properties(bench_peers_synth PROPERTIES LABELS bench FIXTURES_SETUP bench_peers)
add_test(NAME bench_peers_ceres
         COMMAND $<TARGET_FILE:clayfit-peers> ${PEERS_CAPTURE}/capture.json --model M2
                 --peers autodiff,numeric,analytic --start-from-truth ${PEERS_CAPTURE}/truth.json
                 --check)
set_tests_properties(bench_peers_ceres PROPERTIES LABELS bench FIXTURES_REQUIRED bench_peers)
add_test(NAME bench_peers_scipy
         COMMAND sh -c "'${CLAYFIT_PYTHON}' -c 'import numpy, scipy' 2>/dev/null || { echo 'skipped: python3-scipy is not installed'; exit 77; }; exec \"$0\" \"$@\""
                 $<TARGET_FILE:clayfit-peers> ${PEERS_CAPTURE}/capture.json --model M2 --peers scipy
                 --scipy-script ${PROJECT_SOURCE_DIR}/scripts/peer_scipy.py
                 --python ${CLAYFIT_PYTHON} --start-from-truth ${PEERS_CAPTURE}/truth.json --check)
set_tests_properties(bench_peers_scipy PROPERTIES LABELS bench FIXTURES_REQUIRED bench_peers
                     SKIP_RETURN_CODE 77)
