# Rules of the code base that the compiler does not check: the component layout (private headers, layers that import
# only downward, by their includes and by the calls between the library's object files; nothing pointing outside the
# repository) and the formatting (.clang-format).
add_test(NAME layout COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/check_layout.sh $<TARGET_OBJECTS:kergs> WORKING_DIRECTORY ${CMAKE_SOURCE_DIR}
         COMMAND_EXPAND_LISTS)
add_test(NAME format COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/check_format.sh WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(layout format PROPERTIES LABELS "layout" TIMEOUT 60)
# The help tests' checker (tests/expect_output.sh) fails on a non-zero exit, a missing option, an option quoted only in
# another's text and the wrong order: its self-check runs it on stand-ins for each.
add_test(NAME expect_output_self_check COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/expect_output.sh --self-check)
set_tests_properties(expect_output_self_check PROPERTIES LABELS "layout" TIMEOUT 60)
