# scripts/dem_compare --quick (tests/check_dem_compare.py): kergs and LAMMPS on the same compression, the JSON fields,
# force histories of the same order of magnitude. Needs Debian's lammps (scripts/setup.sh).
add_test(NAME dem_compare_quick
         COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/check_dem_compare.py --kergs $<TARGET_FILE:kergs_exe> --dir ${CMAKE_CURRENT_BINARY_DIR}/dem_compare_quick
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(dem_compare_quick PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 2 TIMEOUT 180 LABELS scripts)
# scripts/dem_compare --scene pressure --quick: the deposit pushed by a free wall, both codes, wall histories agreeing.
add_test(NAME dem_compare_pressure_quick
         COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/check_dem_compare.py --scene pressure --kergs $<TARGET_FILE:kergs_exe> --dir ${CMAKE_CURRENT_BINARY_DIR}/dem_compare_pressure_quick
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(dem_compare_pressure_quick PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 2 TIMEOUT 180 LABELS scripts)
# scripts/dem_compare --scene biaxial --quick: compact_small's sample sheared to 0.3 % in both codes; lateral walls at
# sigma3, LAMMPS's overlap at its target, its q/p within 0.08 of kergs's from 0.1 % of axial strain; the cases' friction,
# the macroscopic results and the band (--band) read right.
add_test(NAME dem_compare_biaxial_quick
         COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/check_dem_compare.py --scene biaxial --kergs $<TARGET_FILE:kergs_exe> --dir ${CMAKE_CURRENT_BINARY_DIR}/dem_compare_biaxial_quick
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(dem_compare_biaxial_quick PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 2 TIMEOUT 900 LABELS scripts)
