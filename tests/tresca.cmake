# Solver type tresca (a Tresca fixed point, QPs by TAO): one-contact cases to 1e-10 with the right physics, and
# frictionless confine500 in one Tresca iteration with newton's velocities, for the TAO types that solve its QPs
# (tron, the default, and blmvm), tron on 2 ranks too; the infeasible straight row reported not converged (test_regularised.c).
foreach(tao tron blmvm)
  kergs_test(NAME tresca_${tao} SOURCE test_tresca.c NPROCS 1 ARGS -test_tao_type ${tao})
endforeach()
# the same on 2 ranks (the QP's matrix and vectors are distributed; newton's velocities from 2 ranks too)
kergs_test(NAME tresca_tron_2 SOURCE test_tresca.c NPROCS 2 ARGS -test_tao_type tron)
kergs_test(NAME straight_row_tresca SOURCE test_regularised.c NPROCS 1 ARGS -straight_row_solver tresca -straight_row_steps 2)
