# Rules of the code base that the compiler does not check: the component layout (private headers, io at the end,
# nothing pointing outside the repository) and the formatting (.clang-format).
add_test(NAME layout COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/check_layout.sh WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
add_test(NAME format COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/check_format.sh WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(layout format PROPERTIES LABELS "layout" TIMEOUT 60)
