# scripts/tradeoff --quick on confine5 (tests/check_tradeoff.py): outputs, the named cheapest setting, under a minute.
add_test(NAME tradeoff_quick
         COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/check_tradeoff.py --kergs $<TARGET_FILE:kergs_exe> --dir ${CMAKE_CURRENT_BINARY_DIR}/tradeoff_quick
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(tradeoff_quick PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 2 TIMEOUT 180 LABELS scripts)
# scripts/tradeoff_biaxial --quick on biaxial_small (tests/check_tradeoff_biaxial.py): the macroscopic results per
# setting, the settings applied, the 1- and 2-rank reference band, a comparison row per setting, a killed run
# continued from its checkpoint by --reuse.
add_test(NAME tradeoff_biaxial_quick
         COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/check_tradeoff_biaxial.py --kergs $<TARGET_FILE:kergs_exe>
                 --dir ${CMAKE_CURRENT_BINARY_DIR}/tradeoff_biaxial_quick
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(tradeoff_biaxial_quick PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 2 TIMEOUT 240 LABELS scripts)
