# Siconos cross-checks of kergs's FCLib export (scripts/siconos_solve.py, src/io/fclib_export.c).
#
# 1. Samples with known exact solutions, written through libfclib by tests/data/fclib_samples.c: the script
#    must find Siconos's and the stored solution exact, detect a wrong solution, a changed W, a missing or
#    short dataset, and match a problem whose contacts are reordered.
# 2. The kergs pipeline: kergs exports step 4 of cases/confine5.opts (the step whose line says "step 4"), frictionless
#    and with friction 0.3, on 1 and 2 ranks; Siconos solves it; both residuals must be below 1e-8, the (unique) velocities of the
#    frictionless problem must agree within 1e-6, and the 2-rank file must hold the same W, q, mu as the
#    1-rank one up to the order of the contacts.
# Siconos imports only in Debian's /usr/bin/python3 (Debian package python3-siconos): without it these tests are not registered.

set(KERGS_SICONOS_PYTHON /usr/bin/python3 CACHE FILEPATH "Python interpreter that imports siconos.numerics and h5py")
execute_process(COMMAND ${KERGS_SICONOS_PYTHON} -c "import siconos.numerics, h5py, scipy.sparse"
                RESULT_VARIABLE kergs_siconos_missing OUTPUT_QUIET ERROR_QUIET)
if(kergs_siconos_missing)
  # scripts/setup.sh installs them: a missing one is a broken set-up, reported as a failing test, not a quiet skip
  message(WARNING "${KERGS_SICONOS_PYTHON} cannot import siconos.numerics, h5py and scipy: the Siconos comparison cannot run")
  add_test(NAME siconos_available COMMAND ${CMAKE_COMMAND} -E false)
  return()
endif()

set(SICONOS_DIR ${CMAKE_BINARY_DIR}/siconos_fclib)
set(SICONOS_SOLVE ${KERGS_SICONOS_PYTHON} ${CMAKE_SOURCE_DIR}/scripts/siconos_solve.py)
set(SICONOS_EXPECT_ERROR ${CMAKE_CURRENT_SOURCE_DIR}/expect_error.sh)
file(MAKE_DIRECTORY ${SICONOS_DIR}/samples ${SICONOS_DIR}/export)

# siconos_test(name FIXTURES f1 [f2] ARGS script-arguments... [EXPECT_ERROR regex] [EXPECT_LINE regex])
# EXPECT_LINE: the script must exit 0 and print a line starting with regex (tests/expect_output.sh).
function(siconos_test name)
  cmake_parse_arguments(T "" "EXPECT_ERROR;EXPECT_LINE" "FIXTURES;ARGS" ${ARGN})
  if(DEFINED T_EXPECT_ERROR)
    set(cmd ${SICONOS_EXPECT_ERROR} "${T_EXPECT_ERROR}" ${SICONOS_SOLVE} ${T_ARGS})
  elseif(DEFINED T_EXPECT_LINE)
    set(cmd ${CMAKE_CURRENT_SOURCE_DIR}/expect_output.sh "${T_EXPECT_LINE}" -- ${SICONOS_SOLVE} ${T_ARGS})
  else()
    set(cmd ${SICONOS_SOLVE} ${T_ARGS})
  endif()
  add_test(NAME ${name} COMMAND ${cmd} WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
  set_tests_properties(${name} PROPERTIES FIXTURES_REQUIRED "${T_FIXTURES}" ENVIRONMENT "OPENBLAS_NUM_THREADS=1" TIMEOUT 120)
endfunction()

# ---- 1. samples with known solutions ----------------------------------------------------------------------
find_path(KERGS_HDF5_SERIAL_INCLUDE_DIR hdf5.h PATHS /usr/include/hdf5/serial NO_DEFAULT_PATH)
find_library(KERGS_HDF5_SERIAL_LIBRARY hdf5_serial)
find_library(KERGS_HDF5_SERIAL_HL_LIBRARY hdf5_serial_hl)
if(KERGS_HDF5_SERIAL_INCLUDE_DIR AND KERGS_HDF5_SERIAL_LIBRARY AND KERGS_HDF5_SERIAL_HL_LIBRARY)
  # standalone: libfclib uses the serial HDF5, kergs the MPI one; this program never links kergs
  add_executable(fclib_samples ${CMAKE_CURRENT_SOURCE_DIR}/data/fclib_samples.c)
  target_include_directories(fclib_samples PRIVATE ${FCLIB_INCLUDE_DIR} ${KERGS_HDF5_SERIAL_INCLUDE_DIR})
  target_link_libraries(fclib_samples PRIVATE ${FCLIB_LIBRARY} ${KERGS_HDF5_SERIAL_HL_LIBRARY} ${KERGS_HDF5_SERIAL_LIBRARY} m)
  add_test(NAME siconos_fclib_samples COMMAND fclib_samples ${SICONOS_DIR}/samples)
  set_tests_properties(siconos_fclib_samples PROPERTIES FIXTURES_SETUP siconos_samples TIMEOUT 60)

  set(S ${SICONOS_DIR}/samples)
  foreach(solver nsgs cpg lemke enum)
    siconos_test(siconos_fclib_known_${solver} FIXTURES siconos_samples
                 ARGS ${S}/known.fclib.h5 --solver ${solver} --check-residual 1e-9 --check-u 1e-8 --expect-frictional)
  endforeach()
  siconos_test(siconos_fclib_known_dense FIXTURES siconos_samples
               ARGS ${S}/known.fclib.h5 --storage dense --check-residual 1e-9 --check-u 1e-8)
  siconos_test(siconos_fclib_permuted FIXTURES siconos_samples
               ARGS ${S}/permuted.fclib.h5 --same-as ${S}/known.fclib.h5 --check-residual 1e-9 --check-u 1e-8)
  siconos_test(siconos_fclib_fixed_sweeps FIXTURES siconos_samples EXPECT_LINE "\\{.*\"iterations\": 7, .*\"passed\": true"
               ARGS ${S}/known.fclib.h5 --fixed-sweeps 7 --json)
  siconos_test(siconos_fclib_wrong_solution FIXTURES siconos_samples EXPECT_ERROR "FAILED: kergs residual"
               ARGS ${S}/wrong.fclib.h5 --check-residual 1e-6)
  siconos_test(siconos_fclib_altered FIXTURES siconos_samples EXPECT_ERROR "FAILED: same problem"
               ARGS ${S}/altered.fclib.h5 --same-as ${S}/known.fclib.h5 --no-solve)
  siconos_test(siconos_fclib_altered_block FIXTURES siconos_samples EXPECT_ERROR "FAILED: same problem"
               ARGS ${S}/altered_block.fclib.h5 --same-as ${S}/permuted.fclib.h5 --no-solve)
  siconos_test(siconos_fclib_missing_mu FIXTURES siconos_samples EXPECT_ERROR "missing dataset fclib_local/vectors/mu"
               ARGS ${S}/no_mu.fclib.h5)
  siconos_test(siconos_fclib_short_pointers FIXTURES siconos_samples EXPECT_ERROR "fclib_local/W/p has 12 entries, expected m \\+ 1 = 13"
               ARGS ${S}/bad_p.fclib.h5)
else()
  message(STATUS "Siconos sample tests skipped: serial HDF5 (hdf5.h in /usr/include/hdf5/serial, libhdf5_serial) not found")
endif()

# ---- 2. the kergs pipeline --------------------------------------------------------------------------------
set(E ${SICONOS_DIR}/export)
set(KERGS_FCLIB_RUN -options_file cases/confine5.opts -steps 5 -fclib_step 4 -output_none -quiet
                    -solver_tol 1e-12 -solver_criterion natural -solver_max_it 10000)
add_test(NAME siconos_fclib_clean COMMAND ${CMAKE_COMMAND} -E rm -f ${E}/c5.fclib.h5 ${E}/c5_friction.fclib.h5 ${E}/c5_2ranks.fclib.h5
                                          ${E}/c5_friction_2ranks.fclib.h5)
set_tests_properties(siconos_fclib_clean PROPERTIES FIXTURES_SETUP siconos_clean)

# siconos_export(fixture nprocs file kergs-options...): kergs exports one step's problem into file
function(siconos_export fixture nprocs file)
  add_test(NAME siconos_fclib_export_${fixture}
           COMMAND ${MPIEXEC_EXECUTABLE} ${MPIEXEC_NUMPROC_FLAG} ${nprocs} ${MPIEXEC_PREFLAGS} $<TARGET_FILE:kergs_exe> ${MPIEXEC_POSTFLAGS}
                   ${KERGS_FCLIB_RUN} -fclib_output ${file} ${ARGN}
           WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
  set_tests_properties(siconos_fclib_export_${fixture} PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS ${nprocs} TIMEOUT 120
                       FIXTURES_REQUIRED siconos_clean FIXTURES_SETUP siconos_${fixture})
endfunction()
siconos_export(c5 1 ${E}/c5.fclib.h5 -friction 0)
siconos_export(c5_friction 1 ${E}/c5_friction.fclib.h5 -friction 0.3)
siconos_export(c5_2ranks 2 ${E}/c5_2ranks.fclib.h5 -friction 0)
siconos_export(c5_friction_2ranks 2 ${E}/c5_friction_2ranks.fclib.h5 -friction 0.3)

# frictionless: u (and W r) are unique, so Siconos's and kergs's must agree
siconos_test(siconos_fclib FIXTURES siconos_c5
             ARGS ${E}/c5.fclib.h5 --check-residual 1e-8 --check-u 1e-6 --expect-frictionless --check-min-contacts 4)
# with friction only the residuals are compared: exact solutions may differ (the frictional law need not have a unique solution)
siconos_test(siconos_fclib_frictional FIXTURES siconos_c5_friction
             ARGS ${E}/c5_friction.fclib.h5 --check-residual 1e-8 --expect-frictional --check-min-contacts 4)
# 2 ranks export the same problem as 1 rank, whatever the order of the contacts
siconos_test(siconos_fclib_2ranks FIXTURES siconos_c5 siconos_c5_2ranks
             ARGS ${E}/c5_2ranks.fclib.h5 --same-as ${E}/c5.fclib.h5 --check-residual 1e-8 --check-u 1e-6 --expect-frictionless)
siconos_test(siconos_fclib_2ranks_frictional FIXTURES siconos_c5_friction siconos_c5_friction_2ranks
             ARGS ${E}/c5_friction_2ranks.fclib.h5 --same-as ${E}/c5_friction.fclib.h5 --check-residual 1e-8 --expect-frictional)
