#!/usr/bin/python3
"""kergs at the extremes (docs/running.md, "Stability at the extremes"), through the executable.

  extremes.py GROUP --kergs build/kergs --mpiexec mpiexec --dir WORKDIR

Every case is a row of CASES: a scene (options), the exit status kergs must give, and for a run that must go through
its properties, read from the results file (h5py):
  - every number finite (positions, velocities, impulses, statistics);
  - no grain lost: the same grains at the end as at the start, none behind a wall;
  - interpenetration bounded: the largest interpenetration at most BOUND_FACTOR x (largest relative speed x dt) plus
    the documented floor (OVERLAP_FLOOR of the smallest radius, what a solver stopped at its tolerance leaves);
  - a step the solver did not converge on is reported: marked in /stats/converged, counted on the summary line.
A run that must fail must exit with its documented status and print the message naming what happened.
GROUP selects the rows (the ctest names extremes_GROUP); "all" runs every row."""
import argparse
import os
import re
import subprocess
import sys

import h5py
import numpy as np

from checks import check, failures

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
CONFINE5 = os.path.join(ROOT, "cases", "confine5.opts")
STRAIGHT = os.path.join(ROOT, "cases", "confine5_straight.opts")
CONFINE500 = os.path.join(ROOT, "cases", "confine500.opts")
# the paper's settings, kergs's defaults before they became newton to 1e-8 and the predictive rule: the cases about
# capped NLGS and the paper's gap rule name them
PAPER = ["-solver_type", "nlgs", "-solver_criterion", "quad", "-solver_tol", 1e-4, "-solver_max_it", 150, "-gap_rule", "paper"]
# the pile of radius ratio 100 of docs/running.md: 500 disks of radii 0.5 to 50 mm dropped into an open box, 500 steps
PILE_R100 = ["-scene_name", "r100", "-gravity", "0,-9.81", "-friction", 0.3, "-dt", 1e-3, "-steps", 500, "-disks_source", "random",
             "-random_n", 500, "-random_box", "0,0,1,6", "-random_radius", "0.0005,0.05", "-random_seed", 2013, "-box", "0,0,1,7",
             "-box_open_top"]
BOUND_FACTOR = 2.0  # interpenetration <= BOUND_FACTOR * max relative speed * dt + OVERLAP_FLOOR * smallest radius
OVERLAP_FLOOR = 0.05  # the default -initial_overlap_tol: what kergs accepts in a packing


def column(n, r, gap, mu, dt):
    """A column of n disks of radius r standing on the floor of a box of width 2r, gaps `gap` between them."""
    xs = []
    for i in range(n):
        xs += [r, r + gap + i * (2 * r + gap)]
    h = n * (2 * r + gap) + 2 * r
    return ["-scene_name", "column", "-gravity", "0,-9.81", "-friction", mu, "-dt", dt, "-disks_source", "list",
            "-disks_x", ",".join("%.17g" % x for x in xs), "-disks_radius", r, "-box", "0,0,%g,%g" % (2 * r, h),
            "-box_open_top", "-solver_criterion", "natural", "-solver_tol", 1e-8, "-solver_max_it", 5000]


TC = (1.0 / 9.81) ** 0.5  # characteristic time sqrt(d/g) of disks of diameter 1


def crystal(nx, ny, r, mu=0.3):
    """A square crystal of nx x ny touching disks filling a closed box exactly, under gravity: every contact at once
    (a hyperstatic network: W singular)."""
    return ["-scene_name", "crystal", "-gravity", "0,-9.81", "-friction", mu, "-disks_source", "lattice", "-lattice_type", "square",
            "-lattice_n", "%d,%d" % (nx, ny), "-lattice_radius", r, "-lattice_origin", "%.17g,%.17g" % (r, r),
            "-box", "0,0,%.17g,%.17g" % (2 * r * nx, 2 * r * ny)]


def drop(mu, wall=0.0):
    """A loose hexagonal lattice of 24 disks (radius 0.5, spacing 1.25) falling into a box 9 wide; the right wall moves
    inward at `wall` m/s."""
    return ["-scene_name", "drop", "-gravity", "0,-9.81", "-friction", mu, "-disks_source", "lattice", "-lattice_type", "hex",
            "-lattice_n", "6,4", "-lattice_radius", 0.5, "-lattice_spacing", 1.25, "-lattice_origin", "0.6,0.6", "-box", "0,0,9,10",
            "-box_open_top", "-wall_box_right_velocity", "%g,0" % -wall, "-solver_max_it", 2000]


def heavy_on_light(rsmall, density_big):
    """A big disk (radius 0.5, density `density_big`) resting on a small one (radius rsmall) on the floor, between two
    frictionless walls that centre it: a chain whose mass ratio is density_big / rsmall^2 / 4."""
    return ["-scene_name", "heavy_on_light", "-gravity", "0,-9.81", "-friction", 0, "-materials", 2, "-material_density",
            "1,%g" % density_big, "-disks_source", "list", "-disks_x", "0.5,%.17g,0.5,%.17g" % (rsmall, 2 * rsmall + 0.5),
            "-disks_radius", "%.17g,0.5" % rsmall, "-disks_material", "0,1", "-box", "0,0,1,3", "-box_open_top"]


def one_grain(g):
    return ["-scene_name", "one", "-gravity", "0,%g" % g, "-disks_source", "list", "-disks_x", "0.5,2", "-disks_radius", 0.5,
            "-disks_velocity", "0.3,0", "-box", "-1,0,3,5", "-box_open_top"]


# name: (group, ranks, options, expected status, message regex or None[, {"not_converged": whether some step must be
# reported not converged}])
CASES = {
    # -- the watch: failures kergs must see and report --------------------------------------------------------------
    "blowup_dt": ("watch", 1, ["-options_file", CONFINE500, "-dt", 0.1, "-steps", 30], 2,
                  r"blow-up in step \d+: grain \d+ left the container"),
    "outside_start": ("watch", 2, ["-options_file", CONFINE5, "-disks_x", "-0.6,0.5,1.5,0.53,2.5,0.5,3.5,0.53,4.5,0.5"], 1,
                      r"Grain 0 starts outside the container: its centre is behind wall left"),
    # the divergence rule's report (a natural residual above -solver_divergence_tol 5 steps in a row): forced here by a
    # tolerance no single sweep meets, which is how a diverging kernel solver's residuals (0.78 to 0.93 on the
    # radius-ratio-100 pile, docs/running.md) are caught
    "diverged": ("watch", 1, ["-options_file", CONFINE5, "-solver_max_it", 1, "-solver_divergence_tol", 1e-12], 5,
                 r"the contact solver diverged: natural residual above -solver_divergence_tol 1e-12 in 5 steps in a row, up to step 5"),
    # a genuine divergence: NLGS-Jac on the radius-ratio-100 pile of docs/running.md under the predictive rule, the watch's
    # other rules off (they stop it at step 149 otherwise): its natural residual is 0.78-0.93 from step 198 (r = 0 scores 1)
    "diverged_nlgsjac": ("watch", 1, ["-scene_name", "r100", "-gravity", "0,-9.81", "-friction", 0.3, "-dt", 1e-3, "-steps", 250,
                                      "-disks_source", "random", "-random_n", 500, "-random_box", "0,0,1,6", "-random_radius",
                                      "0.0005,0.05", "-random_seed", 2013, "-box", "0,0,1,7", "-box_open_top", *PAPER, "-solver_type", "nlgsjac",
                                      "-gap_rule", "predictive", "-blowup_overlap", 0, "-blowup_energy", 0], 5,
                         r"the contact solver diverged: natural residual above -solver_divergence_tol 0\.7 in 5 steps in a row, up to step 202"),
    # a kernel projector that misses ker H_f (forced by a check tolerance no factorization meets) fails the step: exit 5
    "kernel_check_nlgsjac": ("watch", 2, ["-options_file", CONFINE5, "-solver_type", "nlgsjac", "-kernel_check_tol", 1e-300], 5,
                             r"the contact solver failed in step 1: DIVERGED_KERNEL, the kernel projector misses ker H_f"),
    "kernel_check_nlkergs": ("watch", 1, ["-options_file", CONFINE5, "-solver_type", "nlkergs", "-kernel_check_tol", 1e-300], 5,
                             r"the contact solver failed in step 1: DIVERGED_KERNEL, the kernel projector misses ker H_f"),
    # the straight row cannot shorten: newton's step 1 is proved infeasible, the run stops there with status 5, naming
    # the grains and walls of the network, and keeps nothing of the step (no row of statistics)
    "infeasible_newton": ("watch", 2, ["-options_file", STRAIGHT, "-solver_type", "newton"], 5,
                          r"step 1 has no solution: the 5 grains 0-4 between walls left, right hold a compressive", {"rows": 0}),
    "infeasible_tresca": ("watch", 1, ["-options_file", STRAIGHT, "-solver_type", "tresca"], 5, r"step 1 has no solution", {"rows": 0}),
    # -on_infeasible continue applies the runaway impulses; the energy watch, which then leaves out the driven wall's work
    # (those impulses'), stops the run as a blow-up
    "infeasible_continue": ("watch", 1, ["-options_file", STRAIGHT, "-solver_type", "newton", "-on_infeasible", "continue"], 2,
                            r"blow-up in step 1: the kinetic energy", {"rows": 1}),
    # velocities finite but beyond what an energy can hold: stopped before the next step's ghost layer works on them
    "gravity_overflow": ("watch", 2, ["-options_file", CONFINE5, "-gravity", "0,-1e300", "-steps", 5], 2,
                         r"blow-up in step 1: the kinetic energy overflows"),
    "outside_box": ("watch", 1, ["-options_file", CONFINE500, "-box", "0,0,0.4,1.2"], 1,
                    r"starts outside the container: its centre is behind wall box_right"),
    # -- time steps from 1e-7 to 1e-1 of the characteristic time ----------------------------------------------------
    "dt_1e-7": ("steps", 1, crystal(4, 4, 0.5) + ["-dt", 1e-7 * TC, "-steps", 5], 0, None),
    "dt_1e-4": ("steps", 1, drop(0.3) + ["-dt", 1e-4 * TC, "-steps", 5], 0, None),
    "dt_1e-1": ("steps", 1, drop(0.3) + ["-dt", 1e-1 * TC, "-steps", 20], 0, None),
    "dt_1e-1_crystal": ("steps", 1, crystal(4, 4, 0.5) + ["-dt", 1e-1 * TC, "-steps", 10], 0, None),
    # -- friction 0, 0.3, 10 ------------------------------------------------------------------------------------------
    "mu_0": ("friction", 1, drop(0) + ["-dt", 5e-3, "-steps", 60], 0, None),
    "mu_0.3": ("friction", 2, drop(0.3) + ["-dt", 5e-3, "-steps", 60], 0, None),
    "mu_10": ("friction", 1, drop(10) + ["-dt", 5e-3, "-steps", 60], 0, None),
    # -- radius ratio 1 to 100, mass ratio 1 to 1e6: a heavy disk on a light one ----------------------------------------
    # (NLGS on this chain converges at a rate 1 - m_small/m_big per sweep: at mass ratio 1e6 it stops at its cap and
    # must say so; Newton solves it)
    "ratio_1": ("ratios", 1, heavy_on_light(0.5, 1) + ["-dt", 1e-3, "-steps", 10, "-disks_x", "0.5,0.5,0.5,1.5"], 0, None),
    "ratio_100_nlgs": ("ratios", 1, heavy_on_light(0.005, 1e2) + PAPER + ["-dt", 1e-3, "-steps", 10], 0, None, {"not_converged": True}),
    "ratio_100_newton": ("ratios", 1, heavy_on_light(0.005, 1e2) + ["-dt", 1e-3, "-steps", 10, "-solver_type", "newton"], 0, None,
                         {"not_converged": False}),
    # the pile of radius ratio 100 of docs/running.md (mass ratio 1e4, grains falling at up to 4.9 m/s) runs through with
    # the defaults, every step converged: it needs newton's second attempt (without it, a step left at residual 0.1
    # throws a grain at 134 m/s: exit 2 at step 164) and the alert distance that follows the speed (with the fixed
    # 0.1 x mean radius, a contact met undetected sinks 0.85 mm into a 0.6 mm grain: exit 2 at step 415)
    "pile_r100": ("ratios", 1, PILE_R100, 0, None, {"not_converged": False}),
    "pile_r100_2": ("ratios", 2, PILE_R100, 0, None, {"not_converged": False}),
    # -- wall speeds from creeping to impact ------------------------------------------------------------------------------
    "wall_creep": ("walls", 1, drop(0.3, 1e-6) + ["-dt", 5e-3, "-steps", 20], 0, None),
    # grains leaving a hopper through its opening fall below the meeting point of its walls' lines: not lost
    "hopper": ("walls", 1, ["-scene_name", "hopper", "-gravity", "0,-9.81", "-friction", 0.3, "-disks_source", "list", "-disks_x",
                            "0.5,1.3,0.44,1.4,0.56,1.5", "-disks_radius", 0.03, "-walls", "left,right", "-wall_left_a", "0,2",
                            "-wall_left_b", "0.45,1", "-wall_right_a", "0.55,1", "-wall_right_b", "1,2", "-dt", 2e-3, "-steps", 200], 0,
               None),
    "wall_impact": ("walls", 1, drop(0.3, 20.0) + ["-dt", 1e-3, "-steps", 80], 0, None),
    # -- one grain, no contact, every contact at once -------------------------------------------------------------------
    "one_grain": ("bodies", 1, one_grain(-9.81) + ["-dt", 1e-2, "-steps", 100], 0, None),
    "no_contact": ("bodies", 2, one_grain(0) + ["-dt", 1e-2, "-steps", 20], 0, None),
}
# the crystal with every solver type (nlkergs stores W~ densely: small enough here)
for _t in ("nlgs", "nlgsjac", "nlkergs", "newton"):
    CASES["crystal_" + _t] = ("crystal", 1, crystal(4, 4, 0.5) + PAPER + ["-dt", 1e-3, "-steps", 5, "-solver_type", _t], 0, None)
    CASES["crystal_predictive_" + _t] = ("crystal", 1, crystal(4, 4, 0.5) + PAPER + ["-dt", 1e-3, "-steps", 5, "-solver_type", _t,
                                                                           "-gap_rule", "predictive"], 0, None)


class Kergs:
    def __init__(self, a):
        self.kergs, self.mpiexec, self.dir = os.path.abspath(a.kergs), a.mpiexec, os.path.abspath(a.dir)

    def run(self, name, ranks, args):
        out = os.path.join(self.dir, name + ".h5")
        cmd = [self.mpiexec, "-n", str(ranks), self.kergs] + [str(x) for x in args] + ["-quiet", "-output", out, "-output_every", "1000000"]
        p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
        with open(os.path.join(self.dir, name + ".log"), "w") as f:
            f.write(" ".join(cmd) + "\n" + p.stdout + p.stderr)
        return p, out


def finite_file(path):
    """Every float dataset of the results file finite."""
    bad = []
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset) and obj.dtype.kind == "f" and obj.size and not np.all(np.isfinite(obj[()])):
                bad.append(name)
        f.visititems(visit)
    return bad


def outside(snap):
    """Grain ids whose centre is behind a wall of the snapshot within the wall's extent (a line anywhere)."""
    x, ids = snap["x"][()], snap["id"][()]
    walls, infinite = snap["walls"][()], snap["wall_infinite"][()]
    lost = set()
    for w, inf in zip(walls, infinite):
        a, b = w[:2], w[2:]
        ab = b - a
        n = np.array([-ab[1], ab[0]]) / np.linalg.norm(ab)
        s = (x - a) @ n
        along = (x - a) @ ab
        behind = (s < 0) & (bool(inf) | ((along >= 0) & (along <= ab @ ab)))
        lost.update(int(i) for i in ids[behind])
    return sorted(lost)


def properties(name, path, stdout, bound_factor=BOUND_FACTOR):
    """The properties every run that goes through must have."""
    bad = finite_file(path)
    check(not bad, f"{name}: every number finite{' (not: ' + ', '.join(bad[:3]) + ')' if bad else ''}")
    with h5py.File(path, "r") as f:
        snaps = [f["snapshots"][k] for k in sorted(f["snapshots"].keys())]
        first, last = snaps[0], snaps[-1]
        out = outside(last)
        check(np.array_equal(np.sort(first["id"][()]), np.sort(last["id"][()])) and not out,
              f"{name}: no grain lost (same grain ids at the end, none behind a wall{': ' + str(out[:5]) if out else ''})")
        st = f["stats"]
        dt = float(st["time"][0]) if st["time"].size else 0.0
        if "step" in st and st["step"].size > 1:
            dt = float(st["time"][1] - st["time"][0])
        rmin = float(np.min(first["radius"][()]))
        # the largest speed relative to anything: twice the fastest grain or wall over the run
        vmax = max(float(np.max(np.linalg.norm(s["v"][()], axis=1))) if s["v"].shape[0] else 0.0 for s in snaps)
        if "wall_velocity" in st:
            vmax = max(vmax, float(np.max(np.abs(st["wall_velocity"][()]))))
        m = re.search(r"fastest grain ([0-9.e+-]+)", stdout)
        if m:
            vmax = max(vmax, float(m.group(1)))
        vrel = 2 * vmax
        worst = float(np.max(st["max_violation"][()])) if st["max_violation"].size else 0.0
        bound = bound_factor * vrel * dt + OVERLAP_FLOOR * rmin
        check(worst <= bound, f"{name}: largest interpenetration {worst:.3g} <= {bound_factor} x relative speed {vrel:.3g} x dt {dt:.3g} "
              f"+ {OVERLAP_FLOOR} x smallest radius = {bound:.3g}")
        conv = st["converged"][()]
        nnot = int(np.sum(conv == 0))
        m = re.search(r"(\d+) not converged", stdout)
        check(m is not None and int(m.group(1)) == nnot,
              f"{name}: steps not converged reported ({nnot} in /stats/converged, summary says {m.group(1) if m else '?'})")
        return st["kinetic_energy"][()].copy() if "kinetic_energy" in st else None


def test_column(k):
    """The predictive gap rule (docs/solver.md): a column of 50 disks whose contacts start at gaps of 1e-10 or 1e-9 is
    at rest within two steps (kinetic energy below 1e-6 m g h, m the column's mass, h its height); under the paper's
    rule, the contrast, its contacts stay out of the solve and the top disk falls freely."""
    n, r, dt = 50, 0.5, 5e-3
    mass = n * np.pi * r * r  # density 1
    bound = 1e-6 * mass * 9.81 * n * 2 * r
    for gap in (1e-10, 1e-9):
        for solver in ("nlgs", "newton"):
            name = f"column_{solver}_{gap:g}"
            p, out = k.run(name, 1, column(n, r, gap, 0.3, dt) + ["-steps", 2, "-gap_rule", "predictive", "-solver_type", solver])
            if not check(p.returncode == 0, f"{name}: predictive rule runs (exit {p.returncode})"):
                continue
            with h5py.File(out, "r") as f:
                ek = f["stats/kinetic_energy"][()]
            check(ek[1] < bound, f"{name}: kinetic energy after 2 steps {ek[1]:.3g} < 1e-6 m g h = {bound:.3g}")
        name = f"column_paper_{gap:g}"
        p, out = k.run(name, 1, column(n, r, gap, 0.3, dt) + ["-steps", 10, "-gap_rule", "paper"])
        with h5py.File(out, "r") as f:
            ek = f["stats/kinetic_energy"][()]
            snaps = f["snapshots"]
            last = snaps[sorted(snaps.keys())[-1]]
            top = int(np.argmax(last["x"][()][:, 1]))
            vtop = float(-last["v"][()][top, 1])
        check(p.returncode == 0 and ek[1] > bound and vtop > 0.8 * 10 * 9.81 * dt,
              f"{name}: under the paper's rule the column falls (kinetic energy after 2 steps {ek[1]:.3g} > {bound:.3g}, "
              f"top disk at {vtop:.3g} m/s after 10 steps, free fall {10 * 9.81 * dt:.3g})")


def run_case(k, name, row):
    group, ranks, args, status, regex = row[:5]
    expect = row[5] if len(row) > 5 else {}
    p, out = k.run(name, ranks, args)
    text = p.stdout + p.stderr
    ok = check(p.returncode == status, f"{name}: exit status {status} (got {p.returncode})")
    if regex:
        check(re.search(regex, text) is not None, f"{name}: the message says /{regex}/")
    if status in (0, 2, 5) and ok and os.path.exists(out):
        if status == 0:
            properties(name, out, p.stdout)
            if "not_converged" in expect:
                with h5py.File(out, "r") as f:
                    nnot = int(np.sum(f["stats/converged"][()] == 0))
                check((nnot > 0) == expect["not_converged"],
                      f"{name}: {'some' if expect['not_converged'] else 'no'} step reported not converged (got {nnot})")
        else:
            with h5py.File(out, "r") as f:
                # the initial snapshot and the last one (the same when the run stopped in its first step)
                check(f.attrs.get("end") is not None and len(f["snapshots"]) >= (1 if expect.get("rows") == 0 else 2),
                      f"{name}: the results file is closed with its end and last snapshot ({f.attrs.get('end')})")
                if "rows" in expect:
                    rows = len(f["stats/step"][()]) if "stats/step" in f else 0
                    check(rows == expect["rows"], f"{name}: {expect['rows']} row(s) of statistics (got {rows})")


SCRIPTED = {"column": test_column}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("group")
    ap.add_argument("--kergs", required=True)
    ap.add_argument("--mpiexec", default="mpiexec")
    ap.add_argument("--dir", required=True)
    a = ap.parse_args()
    os.makedirs(a.dir, exist_ok=True)
    k = Kergs(a)
    rows = {n: r for n, r in CASES.items() if a.group in ("all", r[0])}
    if not rows and a.group not in SCRIPTED:
        sys.exit(f"no case in group {a.group}")
    for name, row in rows.items():
        run_case(k, name, row)
    for g, fn in SCRIPTED.items():
        if a.group in ("all", g):
            fn(k)
    print(f"{a.group}: {len(failures)} failure(s)")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
