# Solver type snesvi (PETSc's SNESVI on the law as a complementarity problem): one-contact cases to 1e-10 with the
# right physics, and frictionless confine500 to 1e-10 with newton's velocities, for both SNESVI types (reduced-space
# active set, the default, and semismooth Fischer-Burmeister), the default also on 2 ranks; the infeasible straight row
# reported not converged (test_regularised.c); a SNES type that ignores the bounds refused.
foreach(type vinewtonrsls vinewtonssls)
  kergs_test(NAME snesvi_${type} SOURCE test_snesvi.c NPROCS 1 ARGS -test_snes_type ${type})
endforeach()
kergs_test(NAME snesvi_vinewtonrsls_2 SOURCE test_snesvi.c NPROCS 2 ARGS -test_snes_type vinewtonrsls)
# Step 1 is flagged (velocity error 1.0). Its answer leaves the row bent, so that step 2's problem is feasible and solved
# (velocity error 4e-7); every later step that begins straight and closed is still checked.
kergs_test(NAME straight_row_snesvi SOURCE test_regularised.c NPROCS 1 ARGS -straight_row_solver snesvi -straight_row_steps 1)
kergs_bad_input(snesvi_not_vi "vinewtonrsls or vinewtonssls" -options_file cases/confine5.opts -solver_type snesvi -solver_snes_type newtonls)
