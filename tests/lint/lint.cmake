# The sources' shape (docs/design.md): no function over 80 lines in the C
# and C++ sources of src/, bench/ and tools/ (tests/lint/check_function_length.py,
# which first checks itself on made-up sources).
add_test(NAME lint_function_length
         COMMAND ${CLAYFIT_PYTHON} ${CMAKE_CURRENT_LIST_DIR}/check_function_length.py
                 ${PROJECT_SOURCE_DIR})
set_tests_properties(lint_function_length PROPERTIES LABELS lint)
