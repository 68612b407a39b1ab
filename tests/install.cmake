# install: cmake --install of this build into a temporary prefix (moved after installing), then examples/ built against
# it with find_package(kergs) and run on 2 ranks: its 2 steps of confine500 must give what the installed executable
# records (tests/check_install.sh). slurm: scripts/slurm/kergs.sbatch parses (bash -n), and its restart chain runs
# against a fake sbatch on PATH (tests/check_slurm.sh).
add_test(NAME install COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/check_install.sh ${CMAKE_BINARY_DIR} ${CMAKE_CURRENT_BINARY_DIR}/install
                              ${MPIEXEC_EXECUTABLE}
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(install PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 2 TIMEOUT 300)
add_test(NAME slurm COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/check_slurm.sh $<TARGET_FILE:kergs_exe> ${CMAKE_CURRENT_BINARY_DIR}/slurm
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(slurm PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" TIMEOUT 300)
