# Solver type newton: the Alart-Curnier Jacobian against finite differences, one-contact cases, the singular wedged
# pair, frictionless confine500 against the unilateral predictor, a line search that is needed (1 rank), and 1 against
# 2 ranks on frictionless confine500.
kergs_test(NAME newton_1 SOURCE test_newton.c NPROCS 1)
kergs_test(NAME newton_2 SOURCE test_newton.c NPROCS 2)
# The interior-point start's KSP given PCREDUNDANT by option: its inner solver's options (-solver_newton_ip_redundant_*,
# read by PETSc only at the first set-up) are known to the unused-option check, and used: the frictionless rest step
# of 300 disks on 2 ranks, J gathered and factored by CHOLMOD on each.
add_test(NAME newton_ip_redundant_options
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/expect_output.sh " +type: redundant" " +type: cholesky" " +type: cholmod" "step +1 .* residual"
                 "kergs: done, exit status 0" --
                 ${MPIEXEC_EXECUTABLE} ${MPIEXEC_NUMPROC_FLAG} 2 ${MPIEXEC_PREFLAGS} $<TARGET_FILE:kergs_exe> ${MPIEXEC_POSTFLAGS}
                 -options_file cases/rest_10k.opts -sample_input cases/compact_small.h5 -friction 0 -solver_tol 1e-8 -output_none
                 -solver_newton_ip_max_it 30 -solver_newton_ip_pc_type redundant -solver_newton_ip_redundant_pc_type cholesky
                 -solver_newton_ip_redundant_pc_factor_mat_solver_type cholmod -solver_newton_ip_ksp_view
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(newton_ip_redundant_options PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 2 TIMEOUT 60)
