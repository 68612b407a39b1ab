# Batch use (docs/running.md): counts that do not fit in the build's 32-bit integers are refused, not wrapped.
kergs_bad_input(steps_overflow "Option .steps: 10000000000 is out of the range" -options_file cases/confine5.opts -steps 10000000000)
# messages that name the option: counts in exponent notation (PETSc's own message names none), a time step that is not finite
kergs_bad_input(steps_exponent_overflow "Option .steps: 1e10 is out of the range" -options_file cases/confine5.opts -steps 1e10)
kergs_bad_input(steps_exponent "Option .steps: 1e3 is not an integer in digits.*write 1000" -options_file cases/confine5.opts -steps 1e3)
# every count read by the scene, the disks, the walls, the partition, the results and the stepper names itself (PETSc's
# parser, reached first, said "Input string 2.5 has no integer value" and no option)
foreach(count random_n random_seed output_every output_flush_every checkpoint_every progress_every solver_divergence_steps
        partition_check_every partition_metis_seed materials wall_box_left_material disks_material fclib_step stop_at_rest_window)
  kergs_bad_input(count_${count} "Option .${count}: 2.5 is not an integer" -options_file cases/compact_small.opts -output_none -${count} 2.5)
endforeach()
kergs_bad_input(count_list "Option .lattice_n: 2.5 is not an integer" -options_file cases/confine5.opts -disks_source lattice -lattice_n 3,2.5)
# a truth value PETSc does not know (its own message, "Unknown logical value", names no option): the option is named,
# read by the stepper, by a solver type, under a wall's prefix, and outside an options block; the words PETSc accepts,
# in any case, still pass
kergs_bad_input(bool_value "Option .quiet: maybe is not a truth value" -options_file cases/confine5.opts -quiet maybe)
kergs_bad_input(bool_value_solver "Option .solver_newton_smoothing: off2 is not a truth value"
                -options_file cases/confine5.opts -solver_type newton -solver_newton_smoothing off2)
kergs_bad_input(bool_value_wall "Option .wall_box_top_guided: maybe is not a truth value"
                -options_file cases/biaxial_small.opts -wall_box_top_guided maybe)
kergs_bad_input(bool_value_fclib "Option .quiet: maybe is not a truth value" -fclib_input tests/data/no_such.fclib.h5 -quiet maybe)
kergs_bad_input(bool_value_unused "Option .allow_unused_options: maybe is not a truth value"
                -options_file cases/confine5.opts -allow_unused_options maybe)
add_test(NAME bool_values_accepted
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/expect_output.sh "kergs: done, exit status 0" --
                 $<TARGET_FILE:kergs_exe> -options_file cases/confine5.opts -steps 1 -output_none -quiet FALSE -disks_lock_rotation Off
                 -box_affine_start no -allow_unused_options 0 -solver_type newton -solver_newton_smoothing YES -solver_newton_project on
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(bool_values_accepted PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" TIMEOUT 60)
kergs_bad_input(dt_inf "Option .dt inf: the time step must be a finite positive number" -options_file cases/confine5.opts -dt inf)
# a failed allocation says so, and where (PETSc's own message was the function's name alone); under a 3 GB address-space
# limit, so that the 6 GB that 400 million disks ask for are refused without touching the machine's memory
add_test(NAME bad_input_out_of_memory
         COMMAND sh -c "ulimit -v 3000000 && exec \"$0\" \"$@\"" ${CMAKE_CURRENT_SOURCE_DIR}/expect_error.sh
                 "out of memory: an allocation in DisksFromLattice failed" $<TARGET_FILE:kergs_exe> -options_file cases/confine5.opts
                 -output_none -disks_source lattice -lattice_n 20000,20000 -lattice_radius 0.0001 -box 0,0,5,5
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(bad_input_out_of_memory PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" TIMEOUT 60)
kergs_bad_input(lattice_overflow "lattice_n 65536,65537 asks for 4295032832 disks"
                -options_file cases/confine5.opts -disks_source lattice -lattice_n 65536,65537 -lattice_radius 0.1)
kergs_bad_input(solver_count_overflow "Option .solver_max_it: 3000000000 is out of the range" -options_file cases/confine5.opts -solver_max_it 3000000000)
# a checkpoint that is missing, or a file that is not a checkpoint
kergs_bad_input(missing_checkpoint "Checkpoint file .-restart. [^ ]*no_such.checkpoint.h5 does not exist" -restart tests/data/no_such.checkpoint.h5)
kergs_bad_input(not_a_checkpoint "deposit500.h5 is not a kergs checkpoint" -restart cases/deposit500.h5)
# a solver type checks its own integer options where it reads them (KergsOptionsInt), kernel and predictor options too
kergs_bad_input(newton_count_overflow "Option .solver_newton_reuse_its: 3000000000 is out of the range"
                -options_file cases/confine5.opts -solver_type newton -solver_newton_reuse_its 3000000000)
# newton's second attempt: a negative rho factor or an empty window is refused, naming the option
kergs_bad_input(newton_second_rho "-solver_newton_second_rho -0.1 must be 0 .none. or positive"
                -options_file cases/confine5.opts -solver_type newton -solver_newton_second_rho -0.1)
kergs_bad_input(newton_second_window "-solver_newton_second_window 0 must be positive"
                -options_file cases/confine5.opts -solver_type newton -solver_newton_second_window 0)
# the working set leaves contacts out of J; the kernel term's projector is over every active contact
kergs_bad_input(newton_working_set_kernel "-solver_newton_working_set needs -solver_prox identity or none"
                -options_file cases/confine5.opts -solver_type newton -solver_prox kernel -solver_newton_working_set)
kergs_bad_input(kernel_count_overflow "Option .kernel_diag_batch: -3000000000 is out of the range"
                -options_file cases/confine5.opts -solver_type nlgsjac -kernel_diag_batch -3000000000)
# a checkpoint's .tmp (a write that did not finish) is not restarted from; an export of a step beyond the run is refused
kergs_bad_input(restart_from_tmp "restart [^ ]*c.checkpoint.h5.tmp is the temporary file of a checkpoint.*restart from [^ ]*c.checkpoint.h5,"
                -restart tests/data/c.checkpoint.h5.tmp)
# a restart of a -box_from_sample run builds its box walls from the run's sample file (relative paths): from another
# directory it is refused with the reason, not "does not exist"
add_test(NAME bad_input_restart_box_from_sample_elsewhere
         COMMAND sh -c "\"$1\" -options_file cases/biaxial_small.opts -steps 1 -output \"$0/rbfs.h5\" -output_every 0 -checkpoint_every 1 -checkpoint_path \"$0/rbfs.checkpoint.h5\" -quiet > /dev/null && cd \"$0\" && exec \"$2\" \"Restart of a run with -box_from_sample: the box walls are built from its sample file cases/compact_small.h5 .* restart in the directory the run started in\" \"$1\" -restart rbfs.checkpoint.h5 -steps 2"
                 ${CMAKE_CURRENT_BINARY_DIR} $<TARGET_FILE:kergs_exe> ${CMAKE_CURRENT_SOURCE_DIR}/expect_error.sh
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(bad_input_restart_box_from_sample_elsewhere PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" TIMEOUT 60 LABELS bad_input)
# a restart takes its options from the checkpoint and can only change their values: turning the rest rule or the
# export off must not meet the refusals of options that would do nothing (-stop_at_rest_stress, -fclib_output)
add_test(NAME restart_turns_options_off
         COMMAND sh -c "\"$1\" -options_file cases/compact_small.opts -steps 2 -stop_at_rest_inertial 1e-4 -stop_at_rest_window 1 -stop_at_rest_stress 0.05 -fclib_step 1 -fclib_output \"$0/rto.fclib.h5\" -output \"$0/rto.h5\" -output_every 0 -checkpoint_every 1 -checkpoint_path \"$0/rto.checkpoint.h5\" -sample_output \"$0/rto_sample.h5\" -quiet > /dev/null && exec \"$1\" -restart \"$0/rto.checkpoint.h5\" -steps 3 -stop_at_rest_inertial 0 -fclib_step -1 -quiet"
                 ${CMAKE_CURRENT_BINARY_DIR} $<TARGET_FILE:kergs_exe>
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(restart_turns_options_off PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" TIMEOUT 60 FIXTURES_SETUP rto)
# that restart's checkpoint holds random disks: a -sample_input given with it is read and not used, and must not stop
# the pass that finds options given without their value
add_test(NAME bad_input_restart_missing_value
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/expect_error.sh "option -initial_overlap_tol is given without its value" $<TARGET_FILE:kergs_exe>
                 -restart ${CMAKE_CURRENT_BINARY_DIR}/rto.checkpoint.h5 -steps 3 -sample_input cases/compact_small.h5 -initial_overlap_tol
                 -output ${CMAKE_CURRENT_BINARY_DIR}/rto_missing.h5
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(bad_input_restart_missing_value PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" TIMEOUT 60 FIXTURES_REQUIRED rto LABELS bad_input)
kergs_bad_input(fclib_step_beyond "fclib_step 50 is beyond the run .-steps 40." -options_file cases/confine5.opts -fclib_step 50)
# an options file that includes itself, directly or through another, is refused before PETSc recurses into it; the
# files an options file includes are inputs that no output may replace
kergs_bad_input(options_file_self "self_include.opts includes itself" -options_file tests/data/self_include.opts)
kergs_bad_input(options_file_cycle "cycle_a.opts includes itself .*cycle_b.opts" -options_file tests/data/cycle_a.opts)
kergs_bad_input(output_on_included_options_file "is the input -options_file cases/confine5.opts"
                -options_file tests/data/includes_confine5.opts -sample_output cases/confine5.opts)

# tests/check_batch.py drives the kergs executable through mpiexec and reads the files with h5py (Debian's python3):
# restart (bit for bit on 2 ranks, 2 -> 1 and 1 -> 2 to the solver's tolerance), signals (SIGTERM, SIGINT to the ranks,
# SIGUSR1 to mpiexec, and to both: delivered twice), kill (SIGKILL leaves a readable .tmp), paths (outputs replacing inputs or each other refused, a
# 300-character path), enospc (a full tmpfs; skipped when none can be mounted), fclib (-fclib_step numbering),
# statuses (exit statuses of a blow-up and of -error_on_nonconvergence, progress lines).
foreach(t restart signals kill paths enospc fclib statuses)
  add_test(NAME batch_${t}
           COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/check_batch.py ${t} --kergs $<TARGET_FILE:kergs_exe> --mpiexec ${MPIEXEC_EXECUTABLE}
                   --dir ${CMAKE_CURRENT_BINARY_DIR}/batch_${t}
           WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
  set_tests_properties(batch_${t} PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 2 TIMEOUT 180 SKIP_RETURN_CODE 77 LABELS batch)
endforeach()
