# -solver_monitor (src/solver/monitor.c): for every solver type on 1 and 2 ranks, one line per iteration, the last
# one carrying the step's recorded residual; the monitor does not change Newton's results (tests/check_monitor.py).
kergs_python_check(solver_monitor check_monitor.py PROCESSORS 2 TIMEOUT 120 LABELS solver)
# the monitor writes text: another viewer type is refused by name
kergs_bad_input(monitor_binary "-solver_monitor writes text" -options_file cases/confine5.opts -steps 1 -solver_monitor binary:${CMAKE_BINARY_DIR}/monitor.bin)
