# kergs at the extremes (docs/running.md, "Stability at the extremes"): tests/extremes.py runs the executable on the
# table of cases of each group and reads the results files with h5py (Debian's python3). Label extremes:
# ctest -L extremes (under 5 minutes on 2 cores).
#   watch     the failures kergs must see: a blow-up (confine500 -dt 0.1: exit 2), grains outside the container at
#             start (exit 1, the grain and the wall named)
#   column    -gap_rule predictive: a column of 50 disks at gaps of 1e-10 and 1e-9 at rest within two steps (nlgs,
#             newton), where the paper's rule lets the top disk fall freely
foreach(g watch column)
  add_test(NAME extremes_${g}
           COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/extremes.py ${g} --kergs $<TARGET_FILE:kergs_exe> --mpiexec ${MPIEXEC_EXECUTABLE}
                   --dir ${CMAKE_CURRENT_BINARY_DIR}/extremes_${g}
           WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
  set_tests_properties(extremes_${g} PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 2 TIMEOUT 300 LABELS extremes)
endforeach()
