# io: results file (stats, snapshots, atomic rename), sample round-trip and bad files, FCLib export read back
# with libfclib; on 1 and 2 ranks. io_plot draws the results file of io_1 with scripts/plot_packing.py and checks the
# picture (tests/check_plot.py: a valid PNG of non-trivial size, not blank).
kergs_test(NAME io_1 SOURCE test_io.c NPROCS 1 ARGS -dir ${CMAKE_CURRENT_BINARY_DIR}/io_1)
kergs_test(NAME io_2 SOURCE test_io.c NPROCS 2 ARGS -dir ${CMAKE_CURRENT_BINARY_DIR}/io_2)
target_include_directories(test_io PRIVATE ${FCLIB_INCLUDE_DIR})
target_compile_definitions(test_io PRIVATE KERGS_FCLIB_LIBRARY="${FCLIB_LIBRARY}")
set_tests_properties(io_1 PROPERTIES FIXTURES_SETUP io_results)
add_test(NAME io_plot
         COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/check_plot.py ${CMAKE_CURRENT_BINARY_DIR}/io_1/sub/results.h5
                 ${CMAKE_CURRENT_BINARY_DIR}/io_1/packing.png
         WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
set_tests_properties(io_plot PROPERTIES FIXTURES_REQUIRED io_results TIMEOUT 120)

# xdmf: the XDMF file beside the results (-output_xdmf) opened headless with ParaView's VTK XDMF reader (vtkXdmfReader,
# Debian's python3-paraview) and compared with the HDF5 file (h5py) at every time step: disk points and radii, contact
# lines and their normal and tangential impulses, walls; after a finished run, a restart and a SIGKILL (tests/check_xdmf.py).
kergs_python_check(xdmf check_xdmf.py PROCESSORS 2 TIMEOUT 180)
