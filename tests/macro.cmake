# The macroscopic response in /stats (src/step/macro.c): every figure recomputed from the snapshot on 1 and 2 ranks, the
# Love-Weber stress of a packing at rest against its boundary (1e-6) and its walls' stress (3 %: the floor's friction),
# a frictionless run without sliding contacts, strains from the walls, zeros without a box (tests/check_macro.py).
add_test(NAME macro_response
         COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/check_macro.py --kergs $<TARGET_FILE:kergs_exe> --mpiexec ${MPIEXEC_EXECUTABLE}
                 --dir ${CMAKE_CURRENT_BINARY_DIR}/macro_response
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(macro_response PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 2 TIMEOUT 120 LABELS step)
# scripts/plot_biaxial.py draws a short run's response as two PNGs (not blank), and refuses a run without a box.
add_test(NAME plot_biaxial
         COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/check_plot_biaxial.py --kergs $<TARGET_FILE:kergs_exe> --mpiexec ${MPIEXEC_EXECUTABLE}
                 --dir ${CMAKE_CURRENT_BINARY_DIR}/plot_biaxial
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(plot_biaxial PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" TIMEOUT 120 LABELS scripts)
