# Contact detection: cell-list search against brute force, ownership by grain id on 2 ranks (each contact found once,
# the union over ranks is the 1-rank brute force), persistence, ghosts refreshed or rebuilt, alert distance.
kergs_test(NAME detect_1 SOURCE test_detect.c NPROCS 1)
kergs_test(NAME detect_2 SOURCE test_detect.c NPROCS 2)
