# Solver type tresca (a Tresca fixed point, QPs by TAO): one-contact cases to 1e-10 with the right physics, and
# frictionless confine500 in one Tresca iteration with newton's velocities, for the TAO types that solve its QPs
# (tron, the default, and blmvm), tron on 2 ranks too; the infeasible straight row reported not converged (test_regularised.c).
foreach(tao tron blmvm)
  kergs_test(NAME tresca_${tao} SOURCE test_tresca.c NPROCS 1 ARGS -test_tao_type ${tao})
endforeach()
# the same on 2 ranks (the QP's matrix and vectors are distributed; newton's velocities from 2 ranks too)
kergs_test(NAME tresca_tron_2 SOURCE test_tresca.c NPROCS 2 ARGS -test_tao_type tron)
kergs_test(NAME straight_row_tresca SOURCE test_regularised.c NPROCS 1 ARGS -straight_row_solver tresca -straight_row_steps 2)
# kergs -help lists the options of every solver type, each under its own heading (PETSc prints a heading's options
# once only: under a shared heading only the first type's appeared), and those of newton's CHOLMOD factorization, which
# PETSc reads only at a first factorization
kergs_test(NAME solver_help NPROCS 1 ARGS -help
           EXPECT_OUTPUT "CHOLMOD Options" -solver_mat_cholmod_dbound "Contact solver type nlkergs options" -solver_nlkergs_max_size
                       "Contact solver type nlgsjac options"
                       "Contact solver type newton options" -solver_newton_rho -solver_newton_redundant_max -solver_newton_ip_max_it
                       -solver_newton_desaxce_max_it -solver_newton_cholesky
                       "Contact solver type tresca options" -solver_tresca_tao_type "Contact solver type snesvi options"
                       -solver_snesvi_shift)
