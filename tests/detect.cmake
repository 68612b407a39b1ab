# Contact detection: cell-list search against brute force, ownership on 2 ranks, persistence, alert distance.
kergs_test(NAME detect_1 SOURCE test_detect.c NPROCS 1)
kergs_test(NAME detect_2 SOURCE test_detect.c NPROCS 2)
