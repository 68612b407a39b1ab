# Kernel projector: projector identities, rank of H_f against dense eigenvalues, exact and bounded diagonal
# blocks of Z, symbolic reuse, empty and fully peeled kernels, null pivots of collinear contacts (MUMPS). Timings:
# scripts/bench_micro.c (scripts/bench).
find_package(LAPACK REQUIRED)
kergs_test(NAME kernel_1 SOURCE test_kernel.c NPROCS 1)
kergs_test(NAME kernel_2 SOURCE test_kernel.c NPROCS 2)
target_link_libraries(test_kernel PRIVATE ${LAPACK_LIBRARIES})
