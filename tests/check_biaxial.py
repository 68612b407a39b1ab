#!/usr/bin/python3
"""The quick biaxial workflow through the executable, one rank a run, two runs at a time: cases/compact_small.opts then
cases/biaxial_small.opts, each also run with another friction, to check physics that can fail.

1. compaction: the run ends at rest (its own -stop_at_rest), the radii follow the area law (r^2 uniform: its mean is
   (rmin^2 + rmax^2)/2 within 3 standard errors), the solid fraction lies in [0.80, 0.83] (measured 0.8167: 300
   frictionless disks of size ratio 2; the loose start is 0.445), and the Love-Weber stress from the contacts equals
   the walls' pressure p in both directions to 1 % (measured 0.2 %), and the sample records its box (/sample/box, where
   the free walls stopped) as its grains' hull to 1e-5 (measured 1e-10), which biaxial_small takes by -box_from_sample;
2. friction and density: the same options on 120 grains in a 0.46 m box (NLGS to quad 1e-4), compacted at mu = 0 and
   at mu = 0.5, both to rest (the case's speed, or 1e-8 J/m per grain: at mu = 0.5 a rattler can go on bouncing at
   6 mm/s under NLGS's 1,000-sweep cap): the frictionless packing ends denser by more than 0.01 (measured 0.8071
   against 0.7895, the walls guided; 0.8070 against 0.7842 free to slide along themselves);
3. biaxial: q/p, 0 at the end of the isotropic compaction (below 0.05, measured 0.012), stays above 0.2 over the run
   (measured 0.33 to 0.44), and strain_axial equals the top wall's travel (from the snapshots' walls) over the initial
   height to 1e-6;
4. Rothenburg-Bathurst along the shear: q/p = (a_c + a_n + a_t)/2 in every row to 0.03 (measured largest gap 0.019 at
   mu = 0.5 and 0.008 frictionless);
5. stress from contacts against stress from walls along the shear, quasi-static (I = 9.5e-4). Frictionless: the
   Love-Weber sxx and syy equal wall_sxx and wall_syy (normal forces over the walls' lengths) averaged over the run to
   2 % (measured 0.08 % and 0.07 %; row by row the median gap is 0.9 % and 0.4 %, the largest 15 %, the walls' and
   grains' inertia). At mu = 0.5 the walls' friction adds to the boundary's stress what wall_sxx leaves out (the
   average sxx is 18 % above it, syy 3 % below), so the Love-Weber stress is checked against the whole boundary's
   (the moment of every wall traction over the box area, friction included) at each snapshot, to 15 %, and on
   average over the snapshots to 3 % (measured largest gap 10.8 %, 2.4 % on average); the lateral walls hold
   sigma3 = 1: wall_sxx averages 1 to 2 % (measured 1.004, 1.003 frictionless);
6. residual strength of frictionless disks: the same shear at -friction 0 ends (mean over the last third of the run)
   at q/p between 0.02 and 0.15 (measured 0.062, at 1.8 % strain: not yet the critical state) and below half
   the frictional run's (measured 0.39);
7. -stop_at_rest_energy alone (the 120 grains of 2, at mu = 0): the run stops at the first step whose kinetic energy
   per grain is below it, after one above;
8. a tiled sample stays at rest: the compaction's sample mirrored into 2 x 3 tiles (scripts/tile_sample.py, 1,800
   grains), TILED_STEPS steps of the same compaction on 2 ranks: the Love-Weber sxx and syy equal p to 1 % in every
   step (measured 0.09 % at step 1, 1e-6 after), the kinetic energy per grain stays below the large compactions' rest
   rule 1e-8 (measured 7.9e-12, the tile's own), the solid fraction is the tile's to 1e-8 (measured 1.2e-9), and the
   tiling's box is the tile's 2 x 3 times. Tiles translated without the mirror leave the grains along the seams
   unsupported (measured: sxx 63 % below p, the energy per grain rising to 3.8e-7 in 10 steps). And tiles (1, 0) and
   (1, 1) of a copy given spins and orientations are that copy reflected in x, and in x and y (a spin left unreversed
   fails it). The contact forces the sample records are mirrored with it: every grain of the tiling is in equilibrium
   under them as well as in the tile (largest net force over the tile's, at most 1 + 1e-9: measured 1; the seams'
   forces left out make it 130 times the tile's), and the tiled run starts from them: its first solve takes at most half the sweeps of
   the same run with -sample_forces false (measured newton 7 against 23). Given tangential forces, the copy's tiles
   (1, 0) and (1, 1) carry them reversed and kept (a reflection reverses the tangent t = (-n_y, n_x)).
9. the force network (scripts/force_network.py on the mu = 0.5 shear, the last 40 % of its strain, 5 snapshots pooled):
   the normal forces are spread as in dense 2D packings (Radjai et al., PRL 77, 274 (1996)): a fraction of them below
   the mean between 0.5 and 0.75 (measured 0.59; an exponential distribution gives 0.63) and a tail P(f) ~ exp(-beta
   f) with beta between 0.5 and 3 (measured 1.19); the strong network (f >= 1) carries most of the deviator (Radjai et
   al., PRL 80, 61 (1998)): q/p of the strong network above the whole's, above the weak one's, whose own is below half
   the whole's in magnitude (measured 0.485, 0.391, 0.123; on the shipped sample cases/compact_small.h5 0.496, 0.362,
   -0.013: the weak network's share of the deviator varies from sample to sample at 300 disks), and the strong network
   carries more than 80 % of the deviator (measured 92 %, 101 % on the shipped sample); a strain window holding no
   snapshot is refused.
10. a run from a sample keeps its own clock: the sample's time attribute (the compaction's, 2.18 s) is the
   preparation's, and the test's time starts at 0, as its step count starts at 1. biaxial_small with the top wall given
   a two-piece program instead of its velocity (-wall_box_top_program 0,0,-V1,2 dt,0,-V2) moves V1 dt on steps 1 and
   2 and V2 dt on step 3 (to 1e-9 of a step's travel), and its time column is dt, 2 dt, 3 dt. On the preparation's
   clock the first piece was skipped and the wall started at V2.
11. -stop_at_rest_inertial alone (the 120 grains of 2, at mu = 0, one rank, a snapshot every step): inertial_number
   is -1 until the window of REST_WINDOW steps has run; the last row, where the run stops, is the first below
   REST_INERTIAL once it has been above with stress_gap within the default -stop_at_rest_stress; stress_gap is
   max |s_ii - boundary_s_ii| / p over the window's rows, and boundary_sxx, boundary_syy are the walls' tractions'
   moment about the box's centre recomputed from the last snapshot; the inertial number is the largest over the four pressure walls of the path the distance to the facing wall
   travelled over the window (the sum of the steps' changes in absolute value) / (the window's time * that distance)
   * d sqrt(rho / p), recomputed from the snapshots' walls to 1e-9 (the ring holds the walls at the start, so the window
   has run at step REST_WINDOW); the solid fraction where it stops is item 2's
   frictionless run's (at rest by the case's speed or 1e-8 J/m per grain) to 0.002 (measured 0.8071 against 0.8071),
   and the Love-Weber sxx and syy equal p to 5 % (measured 0.8 % and 0.8 %, 1 rank). With -stop_at_rest_stress
   REST_STRESS_TIGHT (2 ranks: the rule agreed by both; a snapshot every step there cost 37 s of the suite's time against
   5 s without, HDF5's writes of 16 datasets a snapshot), below the gap where the inertial number first falls below its threshold, rows below it are
   held back and the run stops at the first within it. With -stop_at_rest_stress 0 (2 ranks, as the held run) the inertial number alone
   stops the run, at the first row the tightened run held back, and the message says so rather than "in equilibrium",
   which the other runs' messages say. At mu = 0.5, walls included (1 rank), the walls' friction keeps
   the Love-Weber stress more than FRICTIONAL_OFF off p at rest, and the rule still stops: it compares the Love-Weber
   stress with the boundary's; there too the last row is the first the rule accepts, and stress_gap is recomputed from
   the rows' sxx, syy, boundary_sxx and boundary_syy to 1e-12.

  check_biaxial.py --kergs build/kergs --mpiexec mpiexec --dir WORKDIR
Exit status 0 when every check holds, 1 otherwise."""
import concurrent.futures
import json
import os
import shutil
import subprocess
import sys
import tempfile

import h5py
import numpy as np

from checks import ROOT, Kergs, check, failures

P = 1.0  # -wall_box_<side>_pressure of cases/compact_small.opts (sigma3 of cases/biaxial_small.opts)
RMIN, RMAX = 0.01, 0.02  # its -random_radius
DT = 2e-3  # cases/biaxial_small.opts' -dt
PHI_BAND = (0.80, 0.83)
STRESS_TOL = 0.01
Q_ISOTROPIC, Q_SHEARED = 0.05, 0.2
STRAIN_TOL = 1e-6
BOX_TOL = 1e-5  # the walls at rest against the outermost grains (measured 1e-8)
SMALL_N = 120
REST_ENERGY = 1e-7  # -stop_at_rest_energy of the third small compaction (J/m per grain)
SMALL = ["-random_n", SMALL_N, "-random_box", "0,0,0.46,0.46", "-box", "0,0,0.46,0.46", "-solver_type", "nlgs", "-solver_criterion", "quad",
         "-solver_tol", 1e-4, "-solver_max_it", 1000]
DENSER_BY = 0.01  # frictionless against mu = 0.5 compaction (measured 0.018)
RB_TOL = 0.03  # |q/p - (a_c + a_n + a_t)/2| (measured 0.019)
WALL_MEAN_TOL = 0.02  # run-averaged Love-Weber against wall stress, frictionless (measured 0.1 %)
BOUNDARY_TOL = 0.15  # Love-Weber against the whole boundary's stress at any snapshot, mu = 0.5 (measured 10.8 %)
BOUNDARY_MEAN_TOL = 0.03  # the same, averaged over the snapshots (measured 2.4 %)
SIGMA3_TOL = 0.02  # run-averaged wall_sxx against sigma3 (measured 0.5 %)
Q_FRICTIONLESS = (0.02, 0.15)  # q/p over the last third of the frictionless shear (measured 0.056)
TILES = (2, 3)
TILED_STEPS = 10
BELOW_MEAN = (0.5, 0.75)  # fraction of the normal forces below their mean (measured 0.59)
TAIL_DECAY = (0.5, 3.0)  # beta of the exponential tail (measured 1.19; 1.11 on cases/compact_small.h5)
WEAK_Q = 0.5  # |q/p of the weak network| against the whole's (measured 0.31 here, -0.04 on cases/compact_small.h5)
STRONG_SHARE = 0.8  # the strong network's share of the deviator (measured 0.92; 1.01 on cases/compact_small.h5)
REST_PER_GRAIN = 1e-8  # kinetic energy per grain at rest, -stop_at_rest_energy of the large compactions (J/m)
REST_INERTIAL, REST_WINDOW = 1e-4, 50  # -stop_at_rest_inertial and its default -stop_at_rest_window
RHO = 1.0  # the grains' density (kg/m^2), kergs's default, which cases/compact_small.opts keeps
REST_PHI_TOL = 0.002  # solid fraction at rest by the inertial number against by speed or energy (measured 1e-5)
REST_STRESS_TOL = 0.05  # Love-Weber stress against p where the inertial number stops the run (measured 0.8 %)
REST_STRESS_DEFAULT = 0.05  # kergs's default -stop_at_rest_stress
FRICTIONAL_OFF = 0.02  # the window's Love-Weber stress off p at rest with frictional walls, at least (measured 0.063)
# -stop_at_rest_stress of the held run, far below the gap where the inertial number first falls below its threshold
# (measured 0.0016 at step 820, 32 times above) and within the gap's floor at rest (NLGS to quad 1e-4; measured over
# steps 850 to 1400: median 8e-5, a quarter of the rows within 5e-5): held 133 rows, to step 953 (0.0005 held 7 rows,
# its last at 0.00055); well inside -steps 3000, 0.4 s more of steps.
REST_STRESS_TIGHT = 5e-5


def compaction(k, out, sample, p):
    if not check(p.returncode == 0, "compaction runs (exit %d)" % p.returncode):
        return None
    check("(at rest)" in p.stdout, "compaction ends at rest")
    s = h5py.File(out, "r")["stats"]
    phi, sxx, syy, q = (s[name][-1] for name in ("solid_fraction", "sxx", "syy", "q_over_p"))
    check(PHI_BAND[0] <= phi <= PHI_BAND[1], "solid fraction %.4f in [%.2f, %.2f]" % (phi, *PHI_BAND))
    for name, val in (("sxx", sxx), ("syy", syy)):
        check(abs(val - P) <= STRESS_TOL * P, "%s = %.5f equals the pressure %g to %g" % (name, val, P, STRESS_TOL))
    check(abs(q) < Q_ISOTROPIC, "isotropic at rest: q/p = %.4f below %g" % (q, Q_ISOTROPIC))
    with h5py.File(sample, "r") as f:
        x, r = f["sample/x"][()], f["sample/radius"][()]
        box = f["sample/box"][()].ravel()
    r2, mean = r * r, 0.5 * (RMIN**2 + RMAX**2)
    sem = (RMAX**2 - RMIN**2) / np.sqrt(12 * len(r))
    check(abs(r2.mean() - mean) < 3 * sem, "area law: mean r^2 %.4e against %.4e (+- %.1e)" % (r2.mean(), mean, 3 * sem))
    hull = [(x[:, 0] - r).min(), (x[:, 1] - r).min(), (x[:, 0] + r).max(), (x[:, 1] + r).max()]
    check(np.abs(box - hull).max() < BOX_TOL, "the sample's box %s is its grains' hull to %g" % (np.round(box, 5), BOX_TOL))
    return q


def rest_by_energy(out, p):
    """-stop_at_rest_energy alone: the run stops at the first step whose kinetic energy per grain is below it."""
    if not check(p.returncode == 0 and "(at rest)" in p.stdout, "compaction with -stop_at_rest_energy ends at rest (exit %d)" % p.returncode):
        return
    ek = h5py.File(out, "r")["stats/kinetic_energy"][()] / SMALL_N
    check(len(ek) >= 2 and ek[-1] < REST_ENERGY <= ek[-2], "at rest by energy: %.2e per grain after %.2e, across %g" % (ek[-1], ek[-2], REST_ENERGY))


def step_dt(f):
    """The run's time step, from two consecutive rows' times: the first row's time is dt only on a clock that starts
    at 0 (a results file begun at a restart from step 400 starts at 0.401 s)."""
    time = f["stats/time"]
    return time[-1] - time[-2]


def snapshots_by_step(f):
    """The results file's snapshots by their step attribute: their names count the file's snapshots, which equal the
    steps only for a run that started at step 0 with a snapshot every step (a file begun at a restart from step 400
    names step 931's snapshot 000531)."""
    return {int(g.attrs["step"]): g for g in f["snapshots"].values()}


def box_inertial_number(f, step, window):
    """The box's inertial number over the window ending at step, from the snapshots' walls (rows ax, ay, bx, by): for
    each wall, the path its distance to the facing wall (the opposite side of the box) travels over the window."""
    snaps = snapshots_by_step(f)
    walls = np.array([snaps[i]["walls"][()] for i in range(step - window, step + 1)])
    d = 2 * snaps[step]["radius"][()].mean()
    seconds = window * step_dt(f)
    largest = -1.0
    normal = [np.array([-(by - ay), bx - ax]) / np.hypot(bx - ax, by - ay) for ax, ay, bx, by in walls[-1]]  # inward: left of a -> b
    for w, n in enumerate(normal):
        gap = [(walls[:, j, :2] - walls[:, w, :2]) @ n for j, m in enumerate(normal) if n @ m < -1 + 1e-9]  # antiparallel walls
        gap = min((g for g in gap if g[-1] > 0), key=lambda g: g[-1])  # the facing wall: the nearest in front
        largest = max(largest, np.abs(np.diff(gap)).sum() / (seconds * gap[-1]) * d * np.sqrt(RHO / P))
    return largest


def first_rest_row(f, stress_tol):
    """The rows of /stats as the inertial rule reads them: the index of the first row, once the inertial number has been
    at least REST_INERTIAL, with it below REST_INERTIAL and stress_gap within stress_tol (0: not checked), or None; the
    rows below REST_INERTIAL before it that the stress held back; and the largest difference between stress_gap and
    max |s_ii - b_ii| / p recomputed from the Love-Weber sxx, syy and the boundary's boundary_sxx, boundary_syy averaged
    over the window's REST_WINDOW rows (the box's pressure walls, all at P)."""
    inertial, gap = f["stats/inertial_number"][()], f["stats/stress_gap"][()]
    window = np.ones(REST_WINDOW) / REST_WINDOW
    mean = [np.concatenate([np.full(REST_WINDOW - 1, np.nan), np.convolve(f["stats/" + c][()] - f["stats/boundary_" + c][()], window, "valid")])
            for c in ("sxx", "syy")]
    again = np.maximum(np.abs(mean[0]), np.abs(mean[1])) / P
    armed = np.flatnonzero(inertial >= REST_INERTIAL)
    if len(armed) == 0:
        return None, [], np.inf
    below = [i for i in range(armed[0], len(inertial)) if 0 <= inertial[i] < REST_INERTIAL]
    ok = [i for i in below if stress_tol == 0 or gap[i] <= stress_tol]
    first = ok[0] if ok else None
    held = [i for i in below if first is None or i < first]
    rows = inertial >= 0
    return first, held, np.max(np.abs(gap[rows] - again[rows])) if rows.any() else np.inf


def at_rest_by_inertial(p, checked):
    """Whether the run ended at rest by the inertial rule with the message its -stop_at_rest_stress calls for: the stress
    compared (checked, "(in equilibrium)") or the inertial number alone (-stop_at_rest_stress 0, no such claim)."""
    line = [x for x in p.stdout.splitlines() if x.startswith("kergs: at rest by the inertial number")]
    if checked:
        return p.returncode == 0 and len(line) == 1 and "alone" not in line[0] and line[0].endswith("(in equilibrium)")
    return p.returncode == 0 and len(line) == 1 and line[0].startswith("kergs: at rest by the inertial number alone") and "equilibrium" not in line[0]


def rest_by_inertial(out, p, energy_out):
    """-stop_at_rest_inertial alone: the first step whose box inertial number over the window is below it, with the stress
    inside within the default -stop_at_rest_stress of p, ends the run."""
    if not check(at_rest_by_inertial(p, True), "compaction with -stop_at_rest_inertial ends at rest by it, in equilibrium (exit %d)" % p.returncode):
        return
    with h5py.File(out, "r") as f:
        inertial, steps = f["stats/inertial_number"][()], f["stats/step"][()].astype(int)
        full = inertial[REST_WINDOW - 1:]  # from step REST_WINDOW on: the ring holds the walls at the start too
        first, _, gap_error = first_rest_row(f, REST_STRESS_DEFAULT)
        gap = f["stats/stress_gap"][()]
        check(np.all(inertial[:REST_WINDOW - 1] == -1) and np.all(full >= 0) and first == len(inertial) - 1,
              "inertial_number: -1 before step %d; the last row, %.3e, is the first below %g once above it with stress_gap within %g (%d steps)"
              % (REST_WINDOW, inertial[-1], REST_INERTIAL, REST_STRESS_DEFAULT, len(inertial)))
        check(np.all(gap[:REST_WINDOW - 1] == -1) and np.all(gap[REST_WINDOW - 1:] >= 0), "stress_gap: -1 before step %d, as inertial_number, "
              "and measured from there on" % REST_WINDOW)
        check(gap_error < 1e-12, "stress_gap is max |s_ii - b_ii| / p of the Love-Weber and boundary stresses over the window (to %.1e)" % gap_error)
        snap = snapshots_by_step(f)[steps[-1]]
        bxx, byy = boundary_stress(snap, dt=step_dt(f), centred=True)
        check(abs(bxx - f["stats/boundary_sxx"][-1]) < 1e-9 and abs(byy - f["stats/boundary_syy"][-1]) < 1e-9,
              "boundary_sxx %.9f, boundary_syy %.9f are the walls' tractions' moment about the box's centre, %.9f and %.9f"
              % (f["stats/boundary_sxx"][-1], f["stats/boundary_syy"][-1], bxx, byy))
        again = box_inertial_number(f, steps[-1], REST_WINDOW)
        check(abs(again - inertial[-1]) <= 1e-9 * again, "the box's inertial number %.9e is the walls' displacement's %.9e" % (inertial[-1], again))
        phi, sxx, syy = (f["stats/" + name][-1] for name in ("solid_fraction", "sxx", "syy"))
    check(abs(sxx - P) < REST_STRESS_TOL * P and abs(syy - P) < REST_STRESS_TOL * P,
          "at rest by the inertial number: sxx %.4f, syy %.4f equal p = %g to %g" % (sxx, syy, P, REST_STRESS_TOL))
    phi_energy = h5py.File(energy_out, "r")["stats/solid_fraction"][-1]
    check(abs(phi - phi_energy) < REST_PHI_TOL, "at rest by the inertial number: solid fraction %.4f, by speed or energy %.4f (to %g)"
          % (phi, phi_energy, REST_PHI_TOL))


def rest_held_by_stress(out, p):
    """-stop_at_rest_stress tighter than the stress inside where the walls stop: the run goes on past the rows whose
    inertial number is below the threshold until the stress gap is within it too."""
    if not check(at_rest_by_inertial(p, True),
                 "compaction with -stop_at_rest_stress %g ends at rest by the inertial number, in equilibrium (exit %d)"
                 % (REST_STRESS_TIGHT, p.returncode)):
        return
    with h5py.File(out, "r") as f:
        first, held, _ = first_rest_row(f, REST_STRESS_TIGHT)
        gap, rows = f["stats/stress_gap"][()], len(f["stats/step"])
        check(first == rows - 1 and len(held) > 0,
              "-stop_at_rest_stress %g: the last row (gap %.2g) is the first within it; %d rows below the inertial threshold before it were "
              "held back (gaps %s)" % (REST_STRESS_TIGHT, gap[-1], len(held), ", ".join("%.2g" % gap[i] for i in held[:5])))


def rest_unchecked(out, p, held_out):
    """-stop_at_rest_stress 0: the inertial number alone stops the run, at the first row below REST_INERTIAL once above
    it, and the run's message claims no equilibrium; the held run (the same options and rank, REST_STRESS_TIGHT) went
    the same way up to there, and was held back from exactly that row."""
    if not check(at_rest_by_inertial(p, False),
                 "compaction with -stop_at_rest_stress 0 ends at rest by the inertial number alone, without claiming equilibrium (exit %d)"
                 % p.returncode):
        return
    with h5py.File(out, "r") as f, h5py.File(held_out, "r") as g:
        first, _, _ = first_rest_row(f, 0)
        _, held, _ = first_rest_row(g, REST_STRESS_TIGHT)
        steps, held_steps = f["stats/step"][()].astype(int), g["stats/step"][()].astype(int)
    check(first == len(steps) - 1 and len(held) > 0 and held_steps[held[0]] == steps[-1],
          "-stop_at_rest_stress 0: the last row (step %d) is the first below %g once above it, the first the held run held back "
          "(step %s)" % (steps[-1], REST_INERTIAL, held_steps[held[0]] if held else "none"))


def rest_frictional_walls(out, p):
    """-stop_at_rest_inertial at mu = 0.5, walls included: their friction keeps the Love-Weber stress away from p at
    rest, and the rule still stops, because it compares the Love-Weber stress with the boundary's."""
    if not check(at_rest_by_inertial(p, True),
                 "compaction at mu = 0.5 with -stop_at_rest_inertial ends at rest by it, in equilibrium (exit %d)" % p.returncode):
        return
    with h5py.File(out, "r") as f:
        s = {c: f["stats/" + c][-REST_WINDOW:].mean() for c in ("sxx", "syy", "boundary_sxx", "boundary_syy")}
        gap, rows = f["stats/stress_gap"][-1], len(f["stats/step"])
        first, _, gap_error = first_rest_row(f, REST_STRESS_DEFAULT)
    off = max(abs(s["sxx"] / P - 1), abs(s["syy"] / P - 1))
    check(off > FRICTIONAL_OFF and gap <= REST_STRESS_DEFAULT and first == rows - 1,
          "frictional walls at rest: the window's Love-Weber stress is %.3f off p (sxx %.4f, syy %.4f), the boundary's %.4f, %.4f, "
          "stress_gap %.4f within %g; the last row is the first the rule accepts" % (off, s["sxx"], s["syy"], s["boundary_sxx"],
                                                                                s["boundary_syy"], gap, REST_STRESS_DEFAULT))
    check(gap_error < 1e-12, "frictional walls: stress_gap is max |s_ii - b_ii| / p of the window's Love-Weber and boundary stresses (to %.1e)"
          % gap_error)


def friction_density(k, runs):
    """The small compactions at mu = 0 and mu = 0.5: both at rest, the frictionless one denser."""
    phi = {}
    for mu, (out, p) in runs.items():
        if not check(p.returncode == 0 and "(at rest)" in p.stdout, "small compaction at mu = %s ends at rest (exit %d)" % (mu, p.returncode)):
            return
        phi[mu] = h5py.File(out, "r")["stats/solid_fraction"][-1]
    check(phi[0] - phi[0.5] > DENSER_BY, "frictionless compaction denser: solid fraction %.4f at mu = 0 against %.4f at mu = 0.5 "
          "(more than %g)" % (phi[0], phi[0.5], DENSER_BY))


def boundary_stress(snap, dt=DT, centred=False):
    """The boundary's stress (sxx, syy) at a snapshot: the moment of every wall traction, friction included, over the
    box's area (walls: bottom, right, top, left); equals Love-Weber's in static equilibrium without body forces. With
    centred, the moment about the box's centre, as kergs's boundary_sxx and boundary_syy (out of equilibrium the
    tractions do not sum to zero and the origin counts)."""
    x, rad, a, kind = snap["x"][()], snap["radius"][()], snap["a"][()].astype(int), snap["kind"][()]
    n, r, walls = snap["n"][()], snap["r"][()], snap["walls"][()]
    on = (kind != 0) & (r[:, 0] > 0)
    t = np.stack([-n[:, 1], n[:, 0]], axis=1)
    f = (r[on, :1] * n[on] + r[on, 1:2] * t[on]) / dt
    point = x[a[on]] - rad[a[on]][:, None] * n[on]
    if centred:
        point = point - np.array([0.5 * (walls[1, 0] + walls[3, 0]), 0.5 * (walls[0, 1] + walls[2, 1])])
    area = (walls[1, 0] - walls[3, 0]) * (walls[2, 1] - walls[0, 1])
    return -np.sum(f[:, 0] * point[:, 0]) / area, -np.sum(f[:, 1] * point[:, 1]) / area


def rothenburg_bathurst(tag, s):
    q, half = s["q_over_p"][()], 0.5 * (s["a_c"][()] + s["a_n"][()] + s["a_t"][()])
    gap = np.abs(q - half).max()
    check(gap < RB_TOL, "%s: q/p = (a_c + a_n + a_t)/2 in every row to %.4f (< %g)" % (tag, gap, RB_TOL))


def sigma3(tag, s):
    mean = s["wall_sxx"][()].mean()
    check(abs(mean - P) < SIGMA3_TOL * P, "%s: the lateral walls hold sigma3: wall_sxx averages %.4f (%g to %g)" % (tag, mean, P, SIGMA3_TOL))


def biaxial(k, out, p, q0):
    """The frictional shear: q/p, strain from the walls, Rothenburg-Bathurst, Love-Weber against the boundary."""
    if not check(p.returncode == 0, "biaxial runs (exit %d)" % p.returncode):
        return None
    check("warning: wall" not in p.stdout, "no inertial-number warning at I = 9.5e-4")
    f = h5py.File(out, "r")
    s, snaps = f["stats"], f["snapshots"]
    q = s["q_over_p"][()]
    check(q.min() > Q_SHEARED > q0, "q/p rises from %.4f to [%.3f, %.3f], above %g" % (q0, q.min(), q.max(), Q_SHEARED))
    steps, eps = s["step"][()], s["strain_axial"][()]
    first = snaps[sorted(snaps.keys())[0]]["walls"][()]
    h0 = first[2, 1] - first[0, 1]  # walls: bottom, right, top, left
    worst, boundary = 0.0, []
    for key in sorted(snaps.keys())[1:]:
        g = snaps[key]
        w = g["walls"][()]
        travel = (h0 - (w[2, 1] - w[0, 1])) / h0
        row = np.flatnonzero(steps == g.attrs["step"])[0]
        worst = max(worst, abs(eps[row] - travel))
        bxx, byy = boundary_stress(g)
        boundary += [abs(s["sxx"][row] / bxx - 1), abs(s["syy"][row] / byy - 1)]
    check(worst < STRAIN_TOL and eps[-1] > 0.015, "strain_axial (last %.5f) is the top wall's travel over H0 to %.1e" % (eps[-1], worst))
    rothenburg_bathurst("mu = 0.5", s)
    check(max(boundary) < BOUNDARY_TOL and np.mean(boundary) < BOUNDARY_MEAN_TOL,
          "mu = 0.5: Love-Weber sxx, syy equal the boundary's at %d snapshots to %.3f (< %g), on average to %.3f (< %g)"
          % (len(boundary) // 2, max(boundary), BOUNDARY_TOL, np.mean(boundary), BOUNDARY_MEAN_TOL))
    sigma3("mu = 0.5", s)
    return q[-len(q) // 3:].mean()


def frictionless(k, out, p, q_frictional):
    """The same shear at mu = 0: Rothenburg-Bathurst, Love-Weber against the walls, a small residual strength."""
    if not check(p.returncode == 0, "frictionless biaxial runs (exit %d)" % p.returncode):
        return
    s = h5py.File(out, "r")["stats"]
    rothenburg_bathurst("mu = 0", s)
    for contacts, walls in (("sxx", "wall_sxx"), ("syy", "wall_syy")):
        rel = abs(s[contacts][()].mean() / s[walls][()].mean() - 1)
        check(rel < WALL_MEAN_TOL, "mu = 0: Love-Weber %s equals %s averaged over the run to %.4f (< %g)" % (contacts, walls, rel, WALL_MEAN_TOL))
    sigma3("mu = 0", s)
    q = s["q_over_p"][()]
    q = q[-len(q) // 3:].mean()
    check(Q_FRICTIONLESS[0] < q < Q_FRICTIONLESS[1] and q < 0.5 * q_frictional,
          "mu = 0: residual strength q/p %.4f in (%g, %g), below half the frictional %.4f" % (q, *Q_FRICTIONLESS, q_frictional))


def force_network(k, results):
    """scripts/force_network.py on the frictional shear: the distribution of forces and the strong and weak networks."""
    script = os.path.join(ROOT, "scripts", "force_network.py")
    p = subprocess.run([sys.executable, script, results, "-o", k.path("network")], capture_output=True, text=True)
    if not check(p.returncode == 0, "force_network.py exits 0 %s" % p.stderr[-300:]):
        return
    row = json.loads(p.stdout.strip().splitlines()[-1])
    check(os.path.getsize(k.path("network_forces.png")) > 10000, "force_network.py draws %s" % k.path("network_forces.png"))
    check(BELOW_MEAN[0] < row["below_mean"] < BELOW_MEAN[1] and row["snapshots"] >= 3,
          "%.2f of %d normal forces below the mean, in (%g, %g), over %d snapshots" % (row["below_mean"], row["contacts"], *BELOW_MEAN,
                                                                                       row["snapshots"]))
    check(TAIL_DECAY[0] < row["tail_decay"] < TAIL_DECAY[1], "exponential tail exp(-%.2f f), beta in (%g, %g)" % (row["tail_decay"],
                                                                                                              *TAIL_DECAY))
    strong, whole, weak = row["q_over_p_strong"], row["q_over_p"], row["q_over_p_weak"]
    check(strong > whole > weak and abs(weak) < WEAK_Q * whole,
          "q/p strong %.3f > whole %.3f > weak %.3f, |weak| below %g of the whole" % (strong, whole, weak, WEAK_Q))
    check(row["strong_share_q"] > STRONG_SHARE, "the strong network carries %.0f %% of the deviator (> %.0f %%)" % (100 * row["strong_share_q"],
                                                                                                              100 * STRONG_SHARE))
    lo = 0.5 * (row["strain_window"][0] + row["strain_window"][1])
    p = subprocess.run([sys.executable, script, results, "--from-strain", str(lo), "--to-strain", str(lo), "-o", k.path("none")],
                       capture_output=True, text=True)
    check(p.returncode != 0 and "no snapshot in the strain window" in p.stderr, "an empty window is refused (%s)" % p.stderr.strip())


def tile_sample(source, target):
    p = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "tile_sample.py"), source, target, "--tiles", "%d,%d" % TILES],
                       capture_output=True, text=True)
    check(p.returncode == 0,
          "tile_sample.py tiles %s %d x %d (exit %d) %s" % (os.path.basename(source), *TILES, p.returncode, p.stderr[-300:]))
    return p.returncode == 0


def grain_forces(f, offset, handedness):
    """Rows (a, b, normal force, tangential force) of a sample's grain-grain contacts, ids shifted, sorted."""
    c = f["sample/contacts"]
    grain = c["kind"][()] == 0
    rows = np.column_stack([c["a_id"][()][grain] + offset, c["b_id"][()][grain] + offset, c["force"][()][grain] * [1.0, handedness]])
    return rows[np.lexsort(rows[:, 1::-1].T)]


def tile_forces(g, index, n):
    """The grain-grain contacts of tile `index` of a tiling of n-grain tiles (ids stride n: the sample's are 0..n-1),
    with its ids brought back to the tile's."""
    rows = grain_forces(g, -index * n, 1.0)
    return rows[(rows[:, 0] >= 0) & (rows[:, 1] < n) & (rows[:, 0] < n) & (rows[:, 1] >= 0)]


def mirrored(k, sample):
    """Tiles (1, 0) and (1, 1) of a tiling are the tile reflected in x, and in x and y: positions, velocities, spins
    (reversed by one reflection) and orientations (theta -> pi - theta, then -theta). The frictionless compaction leaves
    no spin, so the tile is a copy of the sample given spins and orientations."""
    spun, tiling = k.path("spun.h5"), k.path("spun_tiled.h5")
    shutil.copyfile(sample, spun)
    with h5py.File(spun, "r+") as f:
        n = len(f["sample/radius"])
        f["sample/omega"][...] = np.linspace(-1.0, 2.0, n)
        f["sample/rot"][...] = np.linspace(-3.0, 3.0, n)
        force, kind = f["sample/contacts/force"], f["sample/contacts/kind"][()]
        force[:, 1] = np.where(kind == 0, np.linspace(-0.01, 0.02, len(kind)), 0.0)  # the walls were frictionless
    if not tile_sample(spun, tiling):
        return
    with h5py.File(spun, "r") as f, h5py.File(tiling, "r") as g:
        x, v, omega, rot = (f["sample"][name][()] for name in ("x", "v", "omega", "rot"))
        box = f["sample/box"][()].ravel()
        size = box[2:] - box[:2]
        for index, flip_y in ((1, False), (TILES[0] + 1, True)):
            part = slice(index * n, (index + 1) * n)
            ex = x.copy()
            ex[:, 0] = box[0] + 2 * size[0] - (x[:, 0] - box[0])
            if flip_y:
                ex[:, 1] = box[1] + 2 * size[1] - (x[:, 1] - box[1])
            want = {"x": ex, "v": v * np.array([-1.0, -1.0 if flip_y else 1.0]), "omega": omega if flip_y else -omega,
                    "rot": rot + np.pi if flip_y else np.pi - rot}
            ok = all(np.allclose(g["sample"][name][part], value, rtol=0, atol=1e-12) for name, value in want.items())
            check(ok and np.abs(v).max() > 0,
                  "tile %d is the tile reflected in x%s: x, v, omega, rot" % (index, " and y" if flip_y else ""))
            check(np.array_equal(tile_forces(g, index, n), grain_forces(f, 0, -1.0 if not flip_y else 1.0)),
                  "tile %d's contacts between grains are the tile's, tangential forces %s" % (index, "kept" if flip_y else "reversed"))


def net_forces(path):
    """Largest net force on a grain from the contact forces a sample records (/sample/contacts), the typical force,
    and the number of contacts. Normals from the positions (disks) or the box walls' inward normals."""
    with h5py.File(path, "r") as f:
        g, c = f["sample"], f["sample/contacts"]
        x, ids = g["x"][()], g["id"][()].astype(int)
        a, kind, b, force = (c[name][()] for name in ("a_id", "kind", "b_id", "force"))
        walls = c.attrs["walls"].decode().split(",")
    index = np.zeros(ids.max() + 1, dtype=int)
    index[ids] = np.arange(len(ids))
    inward = {"box_left": (1.0, 0.0), "box_right": (-1.0, 0.0), "box_bottom": (0.0, 1.0), "box_top": (0.0, -1.0)}
    ia = index[a.astype(int)]
    normal = np.array([inward[walls[int(w)]] for w in np.where(kind == 1, b, 0)])
    grain = kind == 0
    ib = index[np.where(grain, b, ids[0]).astype(int)]
    d = x[ia] - x[ib]
    normal[grain] = d[grain] / np.linalg.norm(d[grain], axis=1)[:, None]
    tangent = np.column_stack([-normal[:, 1], normal[:, 0]])
    vector = force[:, :1] * normal + force[:, 1:] * tangent
    net = np.zeros_like(x)
    np.add.at(net, ia, vector)
    np.add.at(net, ib[grain], -vector[grain])
    return np.abs(net).max(), np.median(force[:, 0]), len(a)


def mirrored_forces(sample, tiled_sample):
    """The tiling's grains are in equilibrium under its mirrored contact forces as the tile's are under its own."""
    tile_net, typical, m = net_forces(sample)
    net, _, mt = net_forces(tiled_sample)
    check(mt > TILES[0] * TILES[1] * m * 0.9 and net <= tile_net * (1 + 1e-9) + 1e-12 * typical,
          "tiled: %d contact forces (tile: %d), the largest net force on a grain %.3g, the tile's %.3g (typical force %.3g)"
          % (mt, m, net, tile_net, typical))


def tiled(k, sample):
    """The compaction's sample mirrored into TILES, at rest under p from its first step (a sample with no box, a bad
    --tiles and an input as output are refused: tests/biaxial.cmake)."""
    tiled_sample, out = k.path("tiled.h5"), k.path("tiled_run.h5")
    if not tile_sample(sample, tiled_sample):
        return
    mirrored(k, sample)
    mirrored_forces(sample, tiled_sample)
    with h5py.File(sample, "r") as f, h5py.File(tiled_sample, "r") as g:
        n, box, tbox = len(f["sample/radius"]), f["sample/box"][()].ravel(), g["sample/box"][()].ravel()
        check(len(g["sample/radius"]) == n * TILES[0] * TILES[1], "the tiling has %d grains" % len(g["sample/radius"]))
    size = np.array([TILES[0] * (box[2] - box[0]), TILES[1] * (box[3] - box[1])])
    check(np.allclose(tbox[:2], box[:2], atol=1e-12) and np.allclose(tbox[2:] - tbox[:2], size, atol=1e-12),
          "the tiling's box %s is the tile's %d x %d times" % (np.round(tbox, 5), *TILES))
    run = ["-options_file", "cases/compact_small.opts", "-disks_source", "file", "-sample_input", tiled_sample, "-box",
           ",".join(repr(float(b)) for b in tbox), "-steps", TILED_STEPS]
    p = k.run(2, *run, "-output", out, "-sample_output", k.path("tiled_out.h5"), log="tiled.log")
    if not check(p.returncode == 0, "the tiled sample runs %d steps of the compaction on 2 ranks (exit %d)" % (TILED_STEPS, p.returncode)):
        return
    cold = k.run(2, *run, "-steps", 1, "-sample_forces", "false", "-output", k.path("tiled_cold.h5"), "-sample_output",
                 k.path("tiled_cold_out.h5"), log="tiled_cold.log")
    s = h5py.File(out, "r")["stats"]
    if check(cold.returncode == 0, "the tiled sample runs from zero impulses (exit %d)" % cold.returncode):
        warm_sweeps, cold_sweeps = s["iterations"][0], h5py.File(k.path("tiled_cold.h5"), "r")["stats/iterations"][0]
        check(warm_sweeps <= cold_sweeps / 2,
              "tiled: the first solve starts from the mirrored forces: %d iterations, %d from zero" % (warm_sweeps, cold_sweeps))
    phi = h5py.File(k.path("compact.h5"), "r")["stats/solid_fraction"][-1]
    worst = max(np.abs(s["sxx"][()] - P).max(), np.abs(s["syy"][()] - P).max())
    check(worst < STRESS_TOL * P, "tiled: Love-Weber sxx, syy equal p in every step to %.2e (< %g)" % (worst, STRESS_TOL))
    energy = s["kinetic_energy"][()].max() / (n * TILES[0] * TILES[1])
    check(energy < REST_PER_GRAIN, "tiled: at rest, kinetic energy per grain at most %.1e (< %g)" % (energy, REST_PER_GRAIN))
    gap = np.abs(s["solid_fraction"][()] - phi).max()
    check(gap < 1e-8, "tiled: the solid fraction is the tile's %.6f to %.1e" % (phi, gap))


def clock(k, sample):
    """A velocity program in the test's time: the run from a sample starts at t = 0."""
    v1, v2 = 0.001, 0.01
    with h5py.File(sample, "r") as f:
        recorded = float(np.ravel(f["sample"].attrs["time"])[0])
    if not check(recorded > 3 * DT, "the sample records its compaction's time, %.4g s: on that clock the program's first piece "
                 "(the first %g s) would be over" % (recorded, 2 * DT)):
        return
    with open(os.path.join(ROOT, "cases/biaxial_small.opts")) as f:
        lines = [line for line in f if not line.startswith("-wall_box_top_velocity")]
    opts = k.path("biaxial_program.opts")
    with open(opts, "w") as f:
        f.writelines(lines)
    out = k.path("biaxial_program.h5")
    p = k.run(1, "-options_file", opts, "-sample_input", sample, "-wall_box_top_program", "0,0,%g,%g,0,%g" % (-v1, 2 * DT, -v2), "-steps", 3,
              "-output", out, "-output_every", 1, "-checkpoint_every", 0, log="biaxial_program.log")
    if not check(p.returncode == 0, "biaxial_small with a top wall program runs (exit %d)" % p.returncode):
        return
    with h5py.File(out, "r") as f:
        snaps = f["snapshots"]
        top = [snaps[key]["walls"][2, 1] for key in sorted(snaps.keys())]  # walls: bottom, right, top, left
        time = f["stats/time"][()]
    travel = -np.diff(top)
    want = np.array([v1, v1, v2]) * DT
    check(np.allclose(time, [DT, 2 * DT, 3 * DT], rtol=0, atol=1e-12) and np.abs(travel - want).max() < 1e-9 * want.max(),
          "a run from a sample starts at t = 0: time %s, the top wall's travel per step %s against the program's %s"
          % (np.round(time, 6), travel, want))


def main():
    k = Kergs.from_command_line(__doc__.splitlines()[0])
    out, sample = k.path("compact.h5"), k.path("sample.h5")
    small = {mu: k.path("small_%g.h5" % mu) for mu in (0, 0.5)}
    # item 11's snapshot of every step, on a RAM file system when there is one: each snapshot is flushed to disk (820
    # of them took 24.5 s on the build's disk, 11 s on /dev/shm)
    fast = tempfile.mkdtemp(prefix="kergs-biaxial-", dir="/dev/shm") if os.access("/dev/shm", os.W_OK) else k.dir
    inertial_out = os.path.join(fast, "small_inertial.h5")
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:  # one rank a run, two runs at a time
        compact = pool.submit(k.run, 1, "-options_file", "cases/compact_small.opts", "-output", out, "-sample_output", sample,
                              log="compact.log")
        smalls = {mu: pool.submit(k.run, 1, "-options_file", "cases/compact_small.opts", *SMALL, "-friction", mu, "-stop_at_rest_energy", REST_PER_GRAIN,
                                  "-output", small[mu],
                                  "-sample_output", k.path("small_%g.sample.h5" % mu), log="small_%g.log" % mu) for mu in (0.5, 0)}
        by_energy = pool.submit(k.run, 1, "-options_file", "cases/compact_small.opts", *SMALL, "-stop_at_rest", 0, "-stop_at_rest_energy",
                                REST_ENERGY, "-output", k.path("small_energy.h5"), "-sample_output", k.path("small_energy.sample.h5"),
                                log="small_energy.log")
        by_inertial = pool.submit(k.run, 1, "-options_file", "cases/compact_small.opts", *SMALL, "-friction", 0, "-stop_at_rest", 0,
                                  "-stop_at_rest_inertial", REST_INERTIAL, "-output_every", 1, "-output", inertial_out,
                                  "-sample_output", k.path("small_inertial.sample.h5"), log="small_inertial.log")
        held = pool.submit(k.run, 2, "-options_file", "cases/compact_small.opts", *SMALL, "-friction", 0, "-stop_at_rest", 0,
                           "-stop_at_rest_inertial", REST_INERTIAL, "-stop_at_rest_stress", REST_STRESS_TIGHT, "-output", k.path("small_held.h5"),
                           "-sample_output", k.path("small_held.sample.h5"), log="small_held.log")
        unchecked = pool.submit(k.run, 2, "-options_file", "cases/compact_small.opts", *SMALL, "-friction", 0, "-stop_at_rest", 0,
                                "-stop_at_rest_inertial", REST_INERTIAL, "-stop_at_rest_stress", 0, "-output", k.path("small_unchecked.h5"),
                                "-sample_output", k.path("small_unchecked.sample.h5"), log="small_unchecked.log")
        frictional = pool.submit(k.run, 1, "-options_file", "cases/compact_small.opts", *SMALL, "-friction", 0.5, "-stop_at_rest", 0,
                                 "-stop_at_rest_inertial", REST_INERTIAL, "-steps", 1500, "-output", k.path("small_frictional.h5"),
                                 "-sample_output", k.path("small_frictional.sample.h5"), log="small_frictional.log")
        q0 = compaction(k, out, sample, compact.result())
        got = q0 is not None
        if got:
            args = ["-options_file", "cases/biaxial_small.opts", "-sample_input", sample]  # its -box_from_sample
            shear = {mu: pool.submit(k.run, 1, *args, "-friction", mu, "-output", k.path("biaxial_%g.h5" % mu), log="biaxial_%g.log" % mu)
                     for mu in (0.5, 0)}
        friction_density(k, {mu: (small[mu], job.result()) for mu, job in smalls.items()})
        rest_by_energy(k.path("small_energy.h5"), by_energy.result())
        rest_by_inertial(inertial_out, by_inertial.result(), small[0])
        rest_held_by_stress(k.path("small_held.h5"), held.result())
        rest_unchecked(k.path("small_unchecked.h5"), unchecked.result(), k.path("small_held.h5"))
        rest_frictional_walls(k.path("small_frictional.h5"), frictional.result())
        if got:
            q_frictional = biaxial(k, k.path("biaxial_0.5.h5"), shear[0.5].result(), q0)
            if q_frictional is not None:
                force_network(k, k.path("biaxial_0.5.h5"))
                frictionless(k, k.path("biaxial_0.h5"), shear[0].result(), q_frictional)
        if got:
            tiled(k, sample)
            clock(k, sample)
    if fast != k.dir:
        shutil.rmtree(fast, ignore_errors=True)
    print("%d failure(s)" % len(failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
