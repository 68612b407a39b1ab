# Tests of the one-contact law (src/solver/law.c) and the NLGS sweep (src/solver/sweep.c).
# law_1: random and hand-made 2x2 and 1x1 problems; the returned impulse satisfies the Signorini-Coulomb law.
kergs_test(NAME law_1 SOURCE test_law.c NPROCS 1 ARGS -fp_trap)
# sweep_1 / sweep_2: hand-built problems (column of disks, lattice W = H^T M^-1 H + s I), solutions against the
# known one and against the 1-rank one, NLGS-Jac entry points. Timing: scripts/bench_micro.c (scripts/bench).
kergs_test(NAME sweep_1 SOURCE test_sweep.c NPROCS 1 ARGS -fp_trap)
kergs_test(NAME sweep_2 SOURCE test_sweep.c NPROCS 2 ARGS -fp_trap)
