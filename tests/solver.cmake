# The solver object: every converged reason a type reaches on confine5 (and /stats's converged agreeing with its sign),
# -solver_converged_reason's lines, and two solvers in one program told apart by an options prefix; 1 and 2 ranks.
kergs_test(NAME solver_1 SOURCE test_solver.c NPROCS 1)
kergs_test(NAME solver_2 SOURCE test_solver.c NPROCS 2)
