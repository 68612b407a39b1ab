# Kernel-regularised solvers (NLKerGS-P, NLGS-Jac) at the extremes of their parameters, on 1 and 2 ranks: finite, the
# recorded residual is the natural residual of the impulses (recomputed by the test), convergence claimed under the
# natural criterion is true of the impulses, a step that hit the cap says so, and plain NLGS reports every step of the
# infeasible straight row not converged.
kergs_test(NAME regularised_1 SOURCE test_regularised.c NPROCS 1)
kergs_test(NAME regularised_2 SOURCE test_regularised.c NPROCS 2)

# The infeasible straight row (cases/confine5_straight.opts) is flagged by every solver type: none of its first steps,
# while the row is straight and the problem has no solution, counts as converged (docs/solver.md, "When a step counts
# as converged": the natural residual alone is fooled there, the velocity error is not), nor any later step that begins
# with the chain closed (newton: from step 3 its row may have been pushed off a wall, a feasible problem).
foreach(case "nlgsjac;linear" "nlgsjac;none" "nlgsjac;elastic" "nlgsjac;unilateral" "nlkergs;linear" "newton;")
  list(GET case 0 solver)
  list(LENGTH case len)
  set(predictor "")
  if(len GREATER 1)
    list(GET case 1 predictor)
  endif()
  if(predictor)
    kergs_test(NAME regularised_straight_row_${solver}_${predictor} SOURCE test_regularised.c NPROCS 1
               ARGS -straight_row_solver ${solver} -straight_row_predictor ${predictor})
  else()
    kergs_test(NAME straight_row_${solver} SOURCE test_regularised.c NPROCS 1 ARGS -straight_row_solver ${solver} -straight_row_steps 2)
  endif()
endforeach()
