# Predictors of NLKerGS-P (src/solver/predictor.c, src/solver/predictors/): column of disks (unilateral exact, linear -> exact
# as eta -> 0), one disk on a floor (closed forms of the elastic and linear predictors, eps 1e-12 .. 1),
# inactive contacts and tangential components zero, a confined hex lattice on 1 rank and on all ranks
# (same r~ within 1e-10, same H_f r~ for the unilateral one), the defining equations of Algorithms 4 and 5,
# bad options.
kergs_test(NAME predictor_1 SOURCE test_predictor.c NPROCS 1 FAIL_REGEX "FAIL ")
kergs_test(NAME predictor_2 SOURCE test_predictor.c NPROCS 2 FAIL_REGEX "FAIL ")
# -help lists every predictor option, each on its own help line, the KSP's under the predictor_ prefix included.
kergs_test(NAME predictor_help SOURCE test_predictor.c NPROCS 1 ARGS -help
           EXPECT_OUTPUT -predictor_type -predictor_eta -predictor_epsilon -predictor_relative -predictor_unilateral_tol
                       -predictor_unilateral_max_it -predictor_pc_type -predictor_ksp_type)
