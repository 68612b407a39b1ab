# kergs -fclib_input (src/io/fclib_import.c, src/step/fclib_run.c, docs/solver.md "Solving FCLib problems"), driven by
# tests/check_fclib_input.py through the executable, files read and written with h5py (Debian's python3):
#   fclib_input_solve   confine500 step 5 exported (friction 0.3 and frictionless) and read back: Newton reaches 1e-10 and
#                       NLGS 1e-8 from r = 0; from the stored solution the import is the run's problem; frictionless, the
#                       run's impulses are found to 1e-8 on 1 and 2 ranks
#   fclib_input_global  a global problem (M, H, f, w) around a known solution: found by Newton and NLGS
#   fclib_input_bad     missing, non-HDF5, non-FCLib, 3D, NaN, short, non-symmetric files, kernel-regularised types: refused
foreach(t solve global bad)
  add_test(NAME fclib_input_${t}
           COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/check_fclib_input.py ${t} --kergs $<TARGET_FILE:kergs_exe>
                   --mpiexec ${MPIEXEC_EXECUTABLE} --dir ${CMAKE_CURRENT_BINARY_DIR}/fclib_input_${t}
           WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
  set_tests_properties(fclib_input_${t} PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 2 TIMEOUT 180 LABELS fclib)
endforeach()
# scripts/profiles --quick: exports 3 small problems, runs kergs's Newton and NLGS and Siconos's fc2d NSGS and fc3d Newton
# on them; the table, the PNG, and every kergs Newton solve at 1e-8
add_test(NAME profiles_quick
         COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/check_profiles.py --dir ${CMAKE_CURRENT_BINARY_DIR}/profiles_quick
                 --kergs $<TARGET_FILE:kergs_exe>
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(profiles_quick PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 1 TIMEOUT 300 LABELS fclib)
# scripts/proto_fixed_points.py (docs/solver.md, "Prototypes measured and not kept"): its methods solve confine5's
# step 3 to kergs's natural residual, and a missing file is refused
add_test(NAME proto_fixed_points
         COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/check_proto_fixed_points.py --kergs $<TARGET_FILE:kergs_exe>
                 --mpiexec ${MPIEXEC_EXECUTABLE}
                 --dir ${CMAKE_CURRENT_BINARY_DIR}/proto_fixed_points
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
set_tests_properties(proto_fixed_points PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 1 TIMEOUT 120 LABELS fclib)
