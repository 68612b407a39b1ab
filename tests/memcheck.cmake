# Memory checks of whole scenes.
#
# 1. In the default run: scenes under PETSc's -malloc_debug -malloc_dump, on 2 ranks. PetscFinalize lists every block
#    allocated through PETSc and never freed ("[ 0] 16 bytes KergsStepperStep() at src/step/stepper.c:109"): any such
#    line fails the test, as does any corruption -malloc_debug detects (non-zero exit). Covers what kergs allocates
#    through PETSc, its objects and registries (every one must be finalized), not MPI's or HDF5's own memory.
set(KERGS_MEMCHECK_DIR ${CMAKE_BINARY_DIR}/memcheck)
file(MAKE_DIRECTORY ${KERGS_MEMCHECK_DIR})
set(KERGS_MALLOC_DUMP_LEAK "\\[ *[0-9]+\\] +[0-9]+ bytes ")
kergs_test(NAME malloc_dump_confine5_nlgs NPROCS 2 FAIL_REGEX "${KERGS_MALLOC_DUMP_LEAK}"
           ARGS -options_file cases/confine5.opts -steps 10 -quiet -malloc_debug -malloc_dump -output ${KERGS_MEMCHECK_DIR}/dump_confine5.h5
                -sample_output ${KERGS_MEMCHECK_DIR}/dump_confine5_sample.h5 -fclib_step 3 -fclib_output ${KERGS_MEMCHECK_DIR}/dump_confine5.fclib.h5)
# -fclib_input reading that export back on 2 ranks
kergs_test(NAME malloc_dump_fclib_input NPROCS 2 FAIL_REGEX "${KERGS_MALLOC_DUMP_LEAK}"
           ARGS -fclib_input ${KERGS_MEMCHECK_DIR}/dump_confine5.fclib.h5 -solver_type newton -solver_max_it 1000 -malloc_debug -malloc_dump
                -output ${KERGS_MEMCHECK_DIR}/dump_fclib_input.h5)
set_tests_properties(malloc_dump_confine5_nlgs PROPERTIES FIXTURES_SETUP dump_confine5_export)
set_tests_properties(malloc_dump_fclib_input PROPERTIES FIXTURES_REQUIRED dump_confine5_export)
kergs_test(NAME malloc_dump_confine5_nlgsjac NPROCS 2 FAIL_REGEX "${KERGS_MALLOC_DUMP_LEAK}"
           ARGS -options_file cases/confine5.opts -steps 5 -quiet -malloc_debug -malloc_dump -output_none
                -solver_type nlgsjac -predictor_type linear -partition_check_every 1 -partition_imbalance_tol 1.0)
# the accurate types, which build PETSc solvers of their own every step (a KSP, a SNES, a Tao), frictional, on 2 ranks
foreach(type newton snesvi tresca)
  kergs_test(NAME malloc_dump_confine5_${type} NPROCS 2 FAIL_REGEX "${KERGS_MALLOC_DUMP_LEAK}"
             ARGS -options_file cases/confine5.opts -steps 5 -quiet -malloc_debug -malloc_dump -output_none -solver_type ${type})
endforeach()
# newton's additive Schwarz (J not gathered): the shell whose subdomain matrices come from W's, W's subdomain, the scatter
kergs_test(NAME malloc_dump_confine5_newton_schwarz NPROCS 2 FAIL_REGEX "${KERGS_MALLOC_DUMP_LEAK}"
           ARGS -options_file cases/confine5.opts -steps 5 -quiet -malloc_debug -malloc_dump -output_none -solver_type newton
                -solver_newton_redundant_max 0)
# newton's De Saxce start: a Tao (BQPIP with a MUMPS Cholesky), E, E^T W E, per step
kergs_test(NAME malloc_dump_rest_newton_desaxce NPROCS 2 FAIL_REGEX "${KERGS_MALLOC_DUMP_LEAK}"
           ARGS -options_file cases/rest_10k.opts -sample_input cases/compact_small.h5 -blowup_energy 0 -quiet -malloc_debug -malloc_dump
                -output_none -solver_newton_desaxce_max_it 4)
# newton's interior-point start: J set up over every contact, then again over the working set (which leaves out the
# contacts whose impulses the start dropped), per step
kergs_test(NAME malloc_dump_rest_newton_ip NPROCS 2 FAIL_REGEX "${KERGS_MALLOC_DUMP_LEAK}"
           ARGS -options_file cases/rest_10k.opts -sample_input cases/compact_small.h5 -blowup_energy 0 -quiet -malloc_debug -malloc_dump
                -output_none -solver_newton_ip_max_it 30)
# the same without friction: the start's one-component LCP of the normal impulses
kergs_test(NAME malloc_dump_rest_newton_ip_frictionless NPROCS 2 FAIL_REGEX "${KERGS_MALLOC_DUMP_LEAK}"
           ARGS -options_file cases/rest_10k.opts -sample_input cases/compact_small.h5 -blowup_energy 0 -friction 0 -quiet -malloc_debug
                -malloc_dump -output_none -solver_newton_ip_max_it 30)
# newton without friction on one rank: J in its symmetric form, factored by CHOLMOD, its work vectors, per step
kergs_test(NAME malloc_dump_rest_newton_cholesky NPROCS 1 FAIL_REGEX "${KERGS_MALLOC_DUMP_LEAK}"
           ARGS -options_file cases/rest_10k.opts -sample_input cases/compact_small.h5 -blowup_energy 0 -friction 0 -steps 2 -quiet
                -malloc_debug -malloc_dump -output_none -solver_newton_smoothing 0)
# newton's working set: J rebuilt over a subset of the contacts when the answer closes a deferred one
kergs_test(NAME malloc_dump_confine5_newton_working_set NPROCS 2 FAIL_REGEX "${KERGS_MALLOC_DUMP_LEAK}"
           ARGS -options_file cases/confine5.opts -steps 5 -quiet -malloc_debug -malloc_dump -output_none -solver_type newton
                -gap_rule predictive -solver_newton_working_set)

# 2. Label memcheck (ctest -L memcheck: about 85 s on 2 cores, 160 s of processor time): scenes under valgrind,
#    failing on any invalid access, use of uninitialised memory or leak (definite, indirect, possible).
#    tests/valgrind.supp suppresses only Open MPI's own memory (MPI_Init/MPI_Finalize, PMIx's progress thread) and
#    libfclib's reader. They are part of the default run too (the whole suite takes about 2 minutes 15 s on 2 cores,
#    so they need no separate configuration); ./scripts/test -LE memcheck leaves them out.
find_program(KERGS_VALGRIND valgrind)
if(NOT KERGS_VALGRIND)
  message(WARNING "valgrind not found (scripts/setup.sh installs it): the memcheck tests cannot run")
  add_test(NAME memcheck_valgrind_available COMMAND ${CMAKE_COMMAND} -E false)
  set_tests_properties(memcheck_valgrind_available PROPERTIES LABELS memcheck)
  return()
endif()
set(KERGS_VALGRIND_CMD ${KERGS_VALGRIND} -q --leak-check=full --errors-for-leak-kinds=definite,indirect,possible --error-exitcode=1
                       --num-callers=50 --suppressions=${CMAKE_CURRENT_SOURCE_DIR}/valgrind.supp)

# kergs_memcheck(name nprocs program args...): program (kergs_exe or a test target) under valgrind on nprocs ranks
function(kergs_memcheck name nprocs program)
  add_test(NAME memcheck_${name}
           COMMAND ${MPIEXEC_EXECUTABLE} ${MPIEXEC_NUMPROC_FLAG} ${nprocs} ${MPIEXEC_PREFLAGS} ${KERGS_VALGRIND_CMD}
                   $<TARGET_FILE:${program}> ${MPIEXEC_POSTFLAGS} ${ARGN}
           WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
  set_tests_properties(memcheck_${name} PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS ${nprocs} TIMEOUT 300 LABELS memcheck)
endfunction()
# plain NLGS with every output: results file, sample, FCLib export (libfclib loaded with dlopen)
kergs_memcheck(confine5_nlgs 1 kergs_exe -options_file cases/confine5.opts -steps 20 -quiet -output ${KERGS_MEMCHECK_DIR}/vg_confine5.h5
               -sample_output ${KERGS_MEMCHECK_DIR}/vg_confine5_sample.h5 -fclib_step 3 -fclib_output ${KERGS_MEMCHECK_DIR}/vg_confine5.fclib.h5)
# NLGS-Jac with the linear predictor on 2 ranks (MUMPS), repartitioned every step (migration of disks and contacts)
kergs_memcheck(confine5_nlgsjac_2 2 kergs_exe -options_file cases/confine5.opts -steps 6 -quiet -output ${KERGS_MEMCHECK_DIR}/vg_confine5_nlgsjac.h5
               -solver_type nlgsjac -predictor_type linear -partition_check_every 1 -partition_imbalance_tol 1.0)
# the 500-disk sample read from cases/deposit500.h5, ghosts and exchanges on 2 ranks
kergs_memcheck(confine500_2 2 kergs_exe -options_file cases/confine500.opts -solver_type nlgs -solver_max_it 150 -solver_tol 1e-4 -steps 3 -quiet -output ${KERGS_MEMCHECK_DIR}/vg_confine500.h5)
# the io test: results and samples written and read back, every refused sample (error paths), FCLib export
kergs_memcheck(io_1 1 test_io -dir ${KERGS_MEMCHECK_DIR}/io)
# -fclib_input reading confine5's export of the test above (libfclib's reader loaded with dlopen), Newton and NLGS
kergs_memcheck(fclib_input_newton 1 kergs_exe -fclib_input ${KERGS_MEMCHECK_DIR}/vg_confine5.fclib.h5 -solver_type newton -solver_max_it 1000
               -output ${KERGS_MEMCHECK_DIR}/vg_fclib_input.h5)
set_tests_properties(memcheck_confine5_nlgs PROPERTIES FIXTURES_SETUP vg_confine5_export)
set_tests_properties(memcheck_fclib_input_newton PROPERTIES FIXTURES_REQUIRED vg_confine5_export)
# confine5's sample of the first test read on 2 ranks, its contact forces (walls matched by name) the first step's warm
# start
kergs_memcheck(sample_forces_2 2 kergs_exe -options_file cases/confine5.opts -disks_source file
               -sample_input ${KERGS_MEMCHECK_DIR}/vg_confine5_sample.h5 -steps 2 -quiet -output ${KERGS_MEMCHECK_DIR}/vg_sample_forces.h5)
set_tests_properties(memcheck_sample_forces_2 PROPERTIES FIXTURES_REQUIRED vg_confine5_export)
# newton's working set under valgrind: J set up again on more rows within a step (confine5 under the predictive rule
# puts a contact back on steps 1 and 2)
kergs_memcheck(confine5_newton_working_set 1 kergs_exe -options_file cases/confine5.opts -steps 3 -quiet -output_none -solver_type newton
               -gap_rule predictive)
