# Partition and migration: same physics on 1 and n ranks, renumbering (METIS every step), warm start across
# swapped pairs, more ranks than grains, all grains on one rank.
kergs_test(NAME partition_1 SOURCE test_partition.c NPROCS 1)
kergs_test(NAME partition_2 SOURCE test_partition.c NPROCS 2)
kergs_test(NAME partition_3 SOURCE test_partition.c NPROCS 3)
