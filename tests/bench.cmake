# Not a test: the micro-benchmarks that scripts/bench runs (scripts/bench_micro.c: NLGS sweep, kernel projector,
# contact detection). Timings are measurements, not pass/fail properties, so they are not in ctest; they are built
# here, with the tests, because they read the same internals (tests/internals.h) and the lattice of tests/lattice.h.
add_executable(kergs_bench_micro ${CMAKE_SOURCE_DIR}/scripts/bench_micro.c)
target_include_directories(kergs_bench_micro PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
target_link_libraries(kergs_bench_micro PRIVATE kergs)
