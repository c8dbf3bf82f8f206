# The sources' shape (docs/design.md): no function over 80 lines in the C
# and C++ sources of src/, bench/ and tools/ (tests/lint/check_function_length.py,
# which first checks itself on made-up sources).
add_test(NAME lint_function_length
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_LIST_DIR}/check_function_length.py
                 ${PROJECT_SOURCE_DIR})
set_tests_properties(lint_function_length PROPERTIES LABELS lint)

# The layering the build enforces (docs/design.md, "Layers"): each layer
# exports only its include/ folder. The probe (layering_probe.c) is built by
# the test, not by default: on clayfit_export, including model's private
# terms.h it must fail on that header, including core's interface it must
# compile (tests/lint/check_layering.py, which also rejects '..' includes
# and src/ itself as an include directory).
add_library(clayfit_layering_probe_interface OBJECT EXCLUDE_FROM_ALL
            ${CMAKE_CURRENT_LIST_DIR}/layering_probe.c)
add_library(clayfit_layering_probe_private OBJECT EXCLUDE_FROM_ALL
            ${CMAKE_CURRENT_LIST_DIR}/layering_probe.c)
target_compile_definitions(clayfit_layering_probe_private PRIVATE CLAYFIT_PROBE_PRIVATE)
foreach(probe clayfit_layering_probe_interface clayfit_layering_probe_private)
  target_link_libraries(${probe} PRIVATE clayfit_export)
endforeach()
add_test(NAME lint_layering
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_LIST_DIR}/check_layering.py
                 ${PROJECT_SOURCE_DIR} ${CMAKE_BINARY_DIR})
set_tests_properties(lint_layering PROPERTIES LABELS lint)
