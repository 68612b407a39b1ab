# -solver_monitor (src/solver/monitor.c): for every solver type on 1 and 2 ranks, one line per iteration, the last
# one carrying the step's recorded residual; the monitor does not change Newton's results (tests/check_monitor.py).
add_test(NAME solver_monitor
         COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/check_monitor.py --kergs $<TARGET_FILE:kergs_exe> --mpiexec ${MPIEXEC_EXECUTABLE}
                 --dir ${CMAKE_CURRENT_BINARY_DIR}/solver_monitor
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(solver_monitor PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 2 TIMEOUT 120 LABELS solver)
# the monitor writes text: another viewer type is refused by name
kergs_bad_input(monitor_binary "-solver_monitor writes text" -options_file cases/confine5.opts -steps 1 -solver_monitor binary:${CMAKE_BINARY_DIR}/monitor.bin)
