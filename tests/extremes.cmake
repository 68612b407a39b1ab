# kergs at the extremes (docs/running.md, "Stability at the extremes"): tests/extremes.py runs the executable on the
# table of cases of each group and reads the results files with h5py (Debian's python3). Label extremes:
# ctest -L extremes (under 5 minutes on 2 cores).
#   watch     the failures kergs must see: a blow-up (confine500 -dt 0.1: exit 2), grains outside the container at
#             start (exit 1, the grain and the wall named), a diverging nlgsjac and a kernel projector
#             that misses ker H_f (exit 5)
#   column    -gap_rule predictive: a column of 50 disks at gaps of 1e-10 and 1e-9 at rest within two steps (nlgs,
#             newton), where the paper's rule lets the top disk fall freely
#   steps     time steps 1e-7, 1e-4 and 1e-1 of the characteristic time sqrt(d/g) (a crystal at rest, a falling lattice)
#   friction  mu = 0, 0.3 (2 ranks), 10 on a falling lattice
#   ratios    radius ratio 1 and 100 with mass ratio up to 1e6: a heavy disk on a light one (nlgs must report its
#             steps not converged; newton solves them)
#   walls     a wall creeping (1e-6 m/s) and one hitting the lattice at 20 m/s; grains leaving a hopper through its
#             opening (not lost)
#   bodies    one grain falling, bouncing off the floor; one grain without any contact (no gravity, 2 ranks)
#   crystal   a square crystal filling a closed box (every contact at once, W singular) with every solver type, under
#             the paper and the predictive gap rules
# Every run that goes through asserts finite numbers, no grain lost, interpenetration <= 2 x relative speed x dt + 5 %
# of the smallest radius, and the steps not converged reported.
foreach(g watch column steps friction ratios walls bodies crystal)
  add_test(NAME extremes_${g}
           COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/extremes.py ${g} --kergs $<TARGET_FILE:kergs_exe> --mpiexec ${MPIEXEC_EXECUTABLE}
                   --dir ${CMAKE_CURRENT_BINARY_DIR}/extremes_${g}
           WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
  set_tests_properties(extremes_${g} PROPERTIES ENVIRONMENT "${KERGS_MPI_ENV}" PROCESSORS 2 TIMEOUT 300 LABELS extremes)
endforeach()
