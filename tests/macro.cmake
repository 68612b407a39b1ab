# The macroscopic response in /stats (src/step/macro.c): every figure recomputed from the snapshot on 1 and 2 ranks, the
# Love-Weber stress of a packing at rest against its boundary (1e-6) and its walls' stress (3 %: the floor's friction),
# a frictionless run without sliding contacts, strains from the walls, zeros without a box (tests/check_macro.py).
kergs_python_check(macro_response check_macro.py PROCESSORS 2 TIMEOUT 120 LABELS step)
# scripts/plot_biaxial.py draws a short run's response as two PNGs (not blank), and refuses a run without a box.
kergs_python_check(plot_biaxial check_plot_biaxial.py TIMEOUT 120 LABELS scripts)
