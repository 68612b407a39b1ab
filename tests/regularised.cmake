# Kernel-regularised solvers (NLKerGS-P, NLGS-Jac) at the extremes of their parameters, on 1 and 2 ranks.
kergs_test(NAME regularised_1 SOURCE test_regularised.c NPROCS 1)
kergs_test(NAME regularised_2 SOURCE test_regularised.c NPROCS 2)
