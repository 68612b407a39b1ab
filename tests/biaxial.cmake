# The quick biaxial workflow: cases/compact_small.opts compacts 300 area-law disks under four pressure walls until at
# rest, cases/biaxial_small.opts shears that sample at constant sigma3; tests/check_biaxial.py checks the physics.
add_test(NAME biaxial_small
         COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/check_biaxial.py --kergs $<TARGET_FILE:kergs_exe> --mpiexec ${MPIEXEC_EXECUTABLE}
                 --dir ${CMAKE_CURRENT_BINARY_DIR}/biaxial_small
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(biaxial_small PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" TIMEOUT 180 LABELS step)
