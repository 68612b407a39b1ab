# Solver type newton: the Alart-Curnier Jacobian against finite differences, one-contact cases, the singular wedged
# pair, frictionless confine500 against the unilateral predictor, a line search that is needed (1 rank), and 1 against
# 2 ranks on frictionless confine500.
kergs_test(NAME newton_1 SOURCE test_newton.c NPROCS 1)
kergs_test(NAME newton_2 SOURCE test_newton.c NPROCS 2)
