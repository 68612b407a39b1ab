#!/usr/bin/python3
"""The accurate end of the speed/accuracy trade: solver type newton against NLGS, in one run, as JSON lines.

Parts (each prints one JSON line per kergs run, then one comparison line with the target and whether it is met):
  confine500  10 steps: newton to natural residual 1e-10 against nlgs to natural 1e-6 (no cap). Target: every step
              <= 1e-10, mean solve time per step <= 1/5 of nlgs's.
  biaxial20k  5 steps: newton to 1e-8 against nlgs to quad 1e-4 (no cap). Target: every step <= 1e-8, in less time.
  pressure20k the same comparison (newton 1e-8, also with -solver_newton_working_set 0, against nlgs quad 1e-4, 5 steps;
              target: 1/5 of nlgs's time; under the paper's gap rule and the predictive one) on a dense polydisperse packing whose
              contact problem does not hang on rounding, unlike the touching lattice of biaxial20k: cases/deposit500.h5
              tiled 40 times along x (20,000 disks, a 20 m x 1 m strip), pushed by a free right wall (1 kg, 20 N, no
              friction against the disks), dt 1e-3 (docs/solver.md, "A polydisperse packing of the same size").
  siconos     confine500's step 5 exported (-fclib_step 5): newton's Newton steps and time on it against Siconos's fc2d
              NSGS at 1e-8 on the same file (scripts/siconos_solve.py), side by side.
  ranks100k   biaxial 100,000, first step, newton to 1e-8 on 1 and on 2 ranks: residuals and speed-up; and the same on
              the polydisperse packing (cases/deposit500.h5 tiled 200 times, 100,000 disks pushed by the free wall
              of pressure20k, 2 steps of 1e-3 s), where the two ranks split the strip along its length.
  snesvi      (not run by default; about 30 s) PETSc's SNESVI (-solver_type snesvi: RSLS, and SSLS without
              friction) against newton, one rank: confine500 (10 steps, 1e-10) and the pressure20k packing tiled 10
              times (5,000 disks, 5 steps, 1e-8), without friction and with (SNESVI capped at 300 iterations a step
              there); steps converged and solve times side by side (docs/solver.md, "PETSc's SNESVI").
  rest10k     (not run by default; about 7 minutes) a dense frictional packing at rest: cases/rest_10k.opts, the
              10,000-disk sample under its pressure with friction 0.5, one step from zero impulses, a problem with a
              solution. newton to 1e-6 (capped at 300 Newton steps) from zero and from the sample's forces, NLGS to
              natural 1e-6 (capped at 30,000 sweeps), and newton without friction as the control; residuals, times, and
              the Love-Weber stress of each answer against the boundary's (the walls' tractions, friction included).
              Then the same step of newton at 300 disks (cases/compact_small.h5), its 2 x 2 and 3 x 3 mirrored tilings
              (scripts/tile_sample.py) and 5,000 disks: Newton steps against size (docs/solver.md, "A dense frictional
              packing at rest").
  ranks40k    (not run by default; about 4 minutes) 1 against 2 ranks on a square polydisperse packing:
              cases/compact_10k.h5 mirrored 2 x 2 (40,000 disks, scripts/tile_sample.py) at rest under its pressure
              walls without friction (cases/rest_10k.opts -friction 0), one step from zero impulses, newton to 1e-6:
              residuals, Newton steps and speed-up (docs/solver.md, "A dense frictional packing at rest").
  square100k  (not run by default; about 4 minutes) 1 against 2 ranks at 100,000 disks on a square packing:
              cases/compact_5k.h5 mirrored 5 x 4 (scripts/tile_sample.py, 11.1 m x 8.5 m) at rest under its pressure
              walls without friction (cases/rest_10k.opts -friction 0), one step from zero impulses, newton to 1e-8
              with the interior-point start (-solver_newton_ip_max_it 40; newton alone took 218 Newton steps and 382 s
              on 2 ranks): residuals, iterations and speed-up (docs/solver.md, "An interior-point start").
  desaxce     (not run by default; about 1 minute) newton's De Saxce start (-solver_newton_desaxce_max_it 6) against
              newton alone on the frictional rest step of cases/rest_10k.opts at 300, 1,200 and 2,700 disks
              (cases/compact_small.h5 and its mirrored tilings), to 1e-8, 300 Newton steps at most: QPs, Newton steps,
              residuals and solve times (docs/solver.md, "A De Saxce start").
  ipstart     (not run by default; about 4 minutes) newton's interior-point start (-solver_newton_ip_max_it 30) against
              newton alone: the frictional rest step of cases/rest_10k.opts at 300, 1,200, 2,700 and 5,000 disks
              (cases/compact_small.h5, its mirrored tilings, cases/compact_5k.h5), to 1e-8, 300 Newton steps at most;
              confine500's 10 steps to 1e-10; the 500-disk pressure scene of scripts/dem_compare at dt 5.5e-3 (20
              steps to 1e-6) and pressure20k's 5 steps to 1e-8 (the predictive gap rule): interior-point iterations,
              Newton steps, residuals and solve times (docs/solver.md, "An interior-point start").
  dt20k       (not run by default; about 5 minutes) pressure20k's 20 ms at the scene's dt (1e-3, newton alone) against
              dt 2e-3 and 5e-3 with newton alone and with the interior-point start, to 1e-8: solve time per simulated
              20 ms and its ratio to the scene's dt (docs/solver.md, "An interior-point start").
  big         (--big only) biaxial 10^6 disks on 2 ranks, first step, newton to 1e-6: time, peak memory per grain.

Usage: bench_accurate.py [--kergs build/kergs] [--parts confine500,biaxial20k,pressure20k,siconos,ranks100k] [--big] [--quick]
--quick: confine500 and siconos only, 5 steps.
Every run is sequential (they do not share the cores); Python from Debian's /usr/bin/python3 (h5py).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("--kergs", default="build/kergs")
ap.add_argument("--parts", default="confine500,biaxial20k,pressure20k,siconos,ranks100k")
ap.add_argument("--big", action="store_true")
ap.add_argument("--quick", action="store_true")
a = ap.parse_args()
env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OPENBLAS_NUM_THREADS="1",
           OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_btl_vader_single_copy_mechanism="none")
tmp = tempfile.mkdtemp(prefix="kergs-accurate.")
parts = a.parts.split(",")
if a.quick:
    parts = [p for p in parts if p in ("confine500", "siconos")]
if a.big:
    parts.append("big")
B100K = ["-options_file", "cases/jammed_lattice.opts", "-lattice_n", "400,250", "-box", "0,0,4.005,2.17009", "-alert", "5e-4"]
B1M = ["-options_file", "cases/jammed_lattice.opts", "-lattice_n", "1000,1000", "-box", "0,0,10.005,8.665254", "-alert", "5e-4"]
NEWTON = ["-solver_type", "newton", "-solver_max_it", "1000"]
IP_START = ["-solver_newton_ip_max_it", "30"]  # newton's interior-point start, as the ipstart and dt20k parts run it


def emit(d):
    print(json.dumps(d), flush=True)


def run(label, ranks, opts):
    """Run kergs; one JSON line with per-step figures; returns the stats (dict of arrays) or None."""
    out = os.path.join(tmp, label + ".h5")
    log = os.path.join(tmp, label + ".log")
    cmd = ["mpiexec", "-n", str(ranks), a.kergs] + opts + ["-output", out, "-quiet"]
    with open(log, "w") as f:
        ok = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT, env=env).returncode == 0
    if not ok:
        emit({"bench": label, "error": "kergs failed, see " + log})
        return None
    with h5py.File(out, "r") as f:
        s = {k: np.asarray(f["stats"][k][()]) for k in f["stats"]}
    row = {"bench": label, "ranks": ranks, "steps": int(len(s["step"])), "options": " ".join(opts),
           "residual_max": float(np.max(s["residual"])), "velocity_error_max": float(np.max(s["velocity_error"])),
           "converged": int(np.sum(s["converged"])), "iterations": [int(x) for x in s["iterations"]],
           "solve_seconds": [round(float(x), 4) for x in s["solve_seconds"]],
           "solve_seconds_mean": float(np.mean(s["solve_seconds"])), "solve_seconds_total": float(np.sum(s["solve_seconds"])),
           "active_mean": float(np.mean(s["active"]))}
    if "peak_memory" in s:
        row["peak_memory_bytes"] = float(np.max(s["peak_memory"]))
        row["baseline_memory_bytes"] = float(s["baseline_memory"][0])
    emit(row)
    return s


if "confine500" in parts:
    n = "5" if a.quick else "10"
    g = run("confine500_nlgs_1e-6", 1, ["-options_file", "cases/confine500.opts", "-steps", n, "-solver_type", "nlgs",
                                         "-solver_criterion", "natural", "-solver_tol", "1e-6", "-solver_max_it", "1000000"])
    w = run("confine500_newton_1e-10", 1, ["-options_file", "cases/confine500.opts", "-steps", n] + NEWTON + ["-solver_tol", "1e-10"])
    if g is not None and w is not None:
        ratio = float(np.mean(w["solve_seconds"]) / np.mean(g["solve_seconds"]))
        every = bool(np.all(w["residual"] <= 1e-10))
        emit({"bench": "confine500", "compare": "newton 1e-10 / nlgs 1e-6, mean solve time per step", "ratio": ratio,
              "newton_every_step_1e-10": every, "target": "every step <= 1e-10 and ratio <= 0.2", "met": every and ratio <= 0.2})

if "biaxial20k" in parts:
    g = run("biaxial20k_nlgs_quad_1e-4", 1, ["-options_file", "cases/jammed_lattice.opts", "-steps", "5", "-solver_max_it", "1000000"])
    w = run("biaxial20k_newton_1e-8", 1, ["-options_file", "cases/jammed_lattice.opts", "-steps", "5"] + NEWTON + ["-solver_tol", "1e-8"])
    if g is not None and w is not None:
        every = bool(np.all(w["residual"] <= 1e-8))
        tg, tw = float(np.sum(g["solve_seconds"])), float(np.sum(w["solve_seconds"]))
        emit({"bench": "biaxial20k", "compare": "newton to 1e-8 against nlgs to quad 1e-4, 5 steps", "nlgs_seconds": tg,
              "newton_seconds": tw, "nlgs_residual_max": float(np.max(g["residual"])), "newton_every_step_1e-8": every,
              "steps_converged_newton": int(np.sum(w["residual"] <= 1e-8)),
              "target": "every step <= 1e-8, in less time than nlgs", "met": every and tw < tg})

def tiled_deposit(tiles):
    """cases/deposit500.h5 repeated `tiles` times along x, every 0.5 m (its box width): a kergs sample file in tmp. The
    disks touching the deposit's side walls face each other across a seam from both sides, so no two overlap."""
    path = os.path.join(tmp, f"deposit{tiles}x.h5")
    with h5py.File("cases/deposit500.h5", "r") as f:
        g = f["sample"]
        d = {k: g[k][()] for k in g}
        n = len(d["radius"])
        with h5py.File(path + ".tmp", "w") as h:
            for k, v in f.attrs.items():
                h.attrs[k] = v
            s = h.create_group("sample")
            for k, v in g.attrs.items():
                s.attrs[k] = v
            s.attrs["ndisks"] = np.asarray(n * tiles, dtype=np.asarray(g.attrs["ndisks"]).dtype).reshape(np.shape(g.attrs["ndisks"]))
            for k, v in d.items():
                if k == "x":
                    v = np.concatenate([v + np.array([0.5 * t, 0.0]) for t in range(tiles)])
                elif k == "id":
                    v = np.concatenate([v + n * t for t in range(tiles)])
                else:
                    v = np.concatenate([v] * tiles)
                s.create_dataset(k, data=v.astype(d[k].dtype))
    os.replace(path + ".tmp", path)
    return path


def pressure_scene(tiles, steps):
    """deposit500 tiled `tiles` times, pushed by a free frictionless right wall (1 kg, 20 N), dt 1e-3."""
    return ["-options_file", "cases/confine500.opts", "-sample_input", tiled_deposit(tiles), "-box", f"0,0,{0.5 * tiles:g},1.2",
            "-wall_box_right_velocity", "0,0", "-wall_box_right_type", "free", "-wall_box_right_mass", "1",
            "-wall_box_right_force", "-20,0", "-materials", "2", "-friction", "0.3", "-friction_pairs", "0,1,0",
            "-wall_box_right_material", "1", "-dt", "1e-3", "-steps", str(steps), "-output_every", "1000", "-output_xdmf", "false"]


if "pressure20k" in parts:
    # as the benchmark was first run (the paper's gap rule, from cases/confine500.opts), and under kergs's default
    # predictive rule, where every contact within the alert distance enters the solve (a third of them open)
    for rule, tag in (("paper", ""), ("predictive", "_predictive")):
        P20K = pressure_scene(40, 5) + ["-gap_rule", rule]
        g = run(f"pressure20k{tag}_nlgs_quad_1e-4", 1, P20K + ["-solver_type", "nlgs", "-solver_tol", "1e-4", "-solver_max_it", "1000000"])
        w = run(f"pressure20k{tag}_newton_1e-8", 1, P20K + NEWTON + ["-solver_tol", "1e-8"])
        w0 = run(f"pressure20k{tag}_newton_1e-8_no_working_set", 1, P20K + NEWTON + ["-solver_tol", "1e-8", "-solver_newton_working_set", "0"])
        for label, r in (("newton", w), ("newton -solver_newton_working_set 0", w0)):
            if g is not None and r is not None:
                every = bool(np.all(r["residual"] <= 1e-8))
                tg, tw = float(np.sum(g["solve_seconds"])), float(np.sum(r["solve_seconds"]))
                emit({"bench": "pressure20k" + tag, "compare": f"{label} to 1e-8 against nlgs to quad 1e-4, 5 steps, gap rule {rule}",
                      "nlgs_seconds": tg, "newton_seconds": tw, "ratio": tw / tg, "nlgs_residual_max": float(np.max(g["residual"])),
                      "newton_every_step_1e-8": every, "target": "every step <= 1e-8, in at most 1/5 of nlgs's time",
                      "met": every and tw <= tg / 5})

if "dt20k" in parts:
    # do time steps 2 and 5 times the scene's cost less per simulated second than the scene's own, at the
    # same residual (<= 1e-8 on every step). The same 20 ms of pressure20k (predictive gap rule): newton alone at the
    # scene's dt, and newton with the interior-point start at the larger ones (docs/solver.md, "An interior-point start")
    base = pressure_scene(40, 1) + NEWTON + ["-gap_rule", "predictive", "-solver_tol", "1e-8"]
    rows = {}
    for dt, steps, extra, tag in (("1e-3", 20, [], "newton"), ("2e-3", 10, IP_START, "newton_ip"), ("5e-3", 4, IP_START, "newton_ip"),
                                  ("2e-3", 10, [], "newton"), ("5e-3", 4, [], "newton")):
        rows[(dt, tag)] = run(f"pressure20k_dt{dt}_{tag}", 1, base + ["-dt", dt, "-steps", str(steps)] + extra)
    ref = rows[("1e-3", "newton")]
    if ref is not None:
        t0 = float(np.sum(ref["solve_seconds"]))
        for (dt, tag), r in rows.items():
            if r is None or (dt, tag) == ("1e-3", "newton"):
                continue
            every = bool(np.all(r["residual"] <= 1e-8)) and bool(np.all(ref["residual"] <= 1e-8))
            t = float(np.sum(r["solve_seconds"]))
            emit({"bench": "dt20k", "setting": f"{tag} dt {dt}", "seconds_per_20ms": t, "scene_dt_seconds_per_20ms": t0, "ratio": t / t0,
                  "every_step_1e-8": every, "target": "a larger dt costs less per simulated second than the scene's, same residual",
                  "met": every and t < t0})

if "snesvi" in parts:
    scenes = {"confine500": (["-options_file", "cases/confine500.opts", "-steps", "10"], "1e-10", []),
              "tiling5k": (pressure_scene(10, 5), "1e-8", ["-friction_pairs", "0,1,0"])}
    types = {"newton": NEWTON, "snesvi_rsls": ["-solver_type", "snesvi"],
             "snesvi_ssls": ["-solver_type", "snesvi", "-solver_snes_type", "vinewtonssls"]}
    for name, (opts, tol, pairs) in scenes.items():
        for mu in ("0", "0.3"):
            rows = {}
            for t, topts in types.items():
                if t == "snesvi_ssls" and mu != "0":
                    continue  # fails from the first frictional step (docs/solver.md)
                cap = ["-solver_max_it", "300"] if t != "newton" and mu != "0" else ["-solver_max_it", "1000"]
                rows[t] = run(f"{name}_mu{mu}_{t}", 1, opts + ["-friction", mu] + pairs + topts + cap + ["-solver_tol", tol])
            if all(r is not None for r in rows.values()):
                emit({"bench": "snesvi", "scene": name, "friction": float(mu), "tol": float(tol),
                      "steps_converged": {t: int(np.sum(r["converged"])) for t, r in rows.items()},
                      "solve_seconds": {t: round(float(np.sum(r["solve_seconds"])), 3) for t, r in rows.items()},
                      "iterations": {t: [int(x) for x in r["iterations"]] for t, r in rows.items()}})

if "siconos" in parts:
    f = os.path.join(tmp, "confine500_step5.fclib.h5")
    w = run("confine500_newton_export5", 1, ["-options_file", "cases/confine500.opts", "-steps", "5"] + NEWTON +
            ["-solver_tol", "1e-10", "-fclib_step", "5", "-fclib_output", f])
    if w is not None and os.path.exists(f):
        res = subprocess.run(["/usr/bin/python3", "scripts/siconos_solve.py", f, "--solver", "nsgs", "--tol", "1e-8",
                              "--max-it", "200000", "--json"], capture_output=True, text=True, env=env)
        try:
            sic = json.loads(res.stdout.strip().splitlines()[-1])
        except (ValueError, IndexError):
            sic = {"error": res.stderr[-500:]}
        # -fclib_step 5 exports the problem of the step whose line says "step 5": row 4 of /stats
        emit({"bench": "siconos", "problem": "confine500 step 5 (-fclib_step 5), warm start from step 4's impulses in kergs",
              "kergs_newton": {"newton_steps": int(w["iterations"][4]), "seconds": float(w["solve_seconds"][4]),
                               "residual": float(w["residual"][4])},
              "siconos_nsgs_1e-8": sic})

if "ranks100k" in parts:
    one = run("biaxial100k_newton_1rank", 1, B100K + ["-steps", "1"] + NEWTON + ["-solver_tol", "1e-8"])
    two = run("biaxial100k_newton_2ranks", 2, B100K + ["-steps", "1"] + NEWTON + ["-solver_tol", "1e-8"])
    if one is not None and two is not None:
        emit({"bench": "ranks100k", "residual_1": float(one["residual"][0]), "residual_2": float(two["residual"][0]),
              "seconds_1": float(one["solve_seconds"][0]), "seconds_2": float(two["solve_seconds"][0]),
              "speedup": float(one["solve_seconds"][0] / two["solve_seconds"][0])})
    P100K = pressure_scene(200, 2)
    one = run("pressure100k_newton_1rank", 1, P100K + NEWTON + ["-solver_tol", "1e-8"])
    two = run("pressure100k_newton_2ranks", 2, P100K + NEWTON + ["-solver_tol", "1e-8"])
    if one is not None and two is not None:
        t1, t2 = float(np.sum(one["solve_seconds"])), float(np.sum(two["solve_seconds"]))
        emit({"bench": "ranks100k_pressure", "residual_max_1": float(np.max(one["residual"])),
              "residual_max_2": float(np.max(two["residual"])), "newton_steps_1": [int(x) for x in one["iterations"]],
              "newton_steps_2": [int(x) for x in two["iterations"]], "seconds_1": t1, "seconds_2": t2, "speedup": t1 / t2})

def tiled_sample(sample, tiles, tiles_y=None):
    """`sample` mirrored into tiles x tiles_y (tiles x tiles if not given) by scripts/tile_sample.py (at rest as
    written): a sample file in tmp."""
    tiles_y = tiles if tiles_y is None else tiles_y
    path = os.path.join(tmp, f"{os.path.splitext(os.path.basename(sample))[0]}_{tiles}x{tiles_y}.h5")
    subprocess.run(["/usr/bin/python3", "scripts/tile_sample.py", sample, path, "--tiles", f"{tiles},{tiles_y}"], check=True,
                   stdout=subprocess.DEVNULL, env=env)
    return path


def over_boundary(s):
    """The Love-Weber stress's sxx and syy over the boundary's (the walls' tractions, friction included), first step."""
    return [round(float(s[c][0] / s["boundary_" + c][0]), 4) for c in ("sxx", "syy")]


if "rest10k" in parts:
    # a capped answer injects energy (docs/solver.md): the blow-up check would end the run with no figures
    REST = ["-options_file", "cases/rest_10k.opts", "-output_every", "1000", "-blowup_energy", "0"]
    rows = {"newton": run("rest10k_newton_1e-6", 1, REST),
            "newton_from_sample_forces": run("rest10k_newton_1e-6_sample_forces", 1, REST + ["-sample_forces", "true"]),
            "nlgs": run("rest10k_nlgs_natural_1e-6", 1, REST + ["-solver_type", "nlgs", "-solver_criterion", "natural",
                                                               "-solver_max_it", "30000"]),
            "newton_frictionless": run("rest10k_newton_1e-6_frictionless", 1, REST + ["-friction", "0"])}
    if all(r is not None for r in rows.values()):
        emit({"bench": "rest10k", "residual": {k: float(r["residual"][0]) for k, r in rows.items()},
              "converged": {k: bool(r["converged"][0]) for k, r in rows.items()},
              "iterations": {k: int(r["iterations"][0]) for k, r in rows.items()},
              "solve_seconds": {k: round(float(r["solve_seconds"][0]), 2) for k, r in rows.items()},
              "kinetic_energy_after": {k: float(r["kinetic_energy"][0]) for k, r in rows.items()},
              "love_weber_over_boundary": {k: over_boundary(r) for k, r in rows.items()},
              "target": "newton converges (1e-6) with friction as without", "met": bool(rows["newton"]["converged"][0])})
    samples = {"300": "cases/compact_small.h5", "1200": tiled_sample("cases/compact_small.h5", 2),
               "2700": tiled_sample("cases/compact_small.h5", 3), "5000": "cases/compact_5k.h5"}
    sizes = {n: run(f"rest{n}_newton_1e-6", 1, REST + ["-sample_input", path]) for n, path in samples.items()}
    sizes["10000"] = rows["newton"]
    if all(r is not None for r in sizes.values()):
        emit({"bench": "rest_sizes", "disks": [int(n) for n in sizes], "newton_steps": [int(r["iterations"][0]) for r in sizes.values()],
              "residual": [float(r["residual"][0]) for r in sizes.values()],
              "solve_seconds": [round(float(r["solve_seconds"][0]), 2) for r in sizes.values()],
              "love_weber_over_boundary": [over_boundary(r) for r in sizes.values()]})

# the frictional rest step to 1e-8 on the 300-disk sample and its mirrored tilings: where newton's two starts are compared
REST_1E8 = ["-options_file", "cases/rest_10k.opts", "-output_every", "1000", "-blowup_energy", "0", "-solver_tol", "1e-8"]


def rest_samples():
    return {"300": "cases/compact_small.h5", "1200": tiled_sample("cases/compact_small.h5", 2),
            "2700": tiled_sample("cases/compact_small.h5", 3)}


if "desaxce" in parts:
    for n, path in rest_samples().items():
        alone = run(f"rest{n}_newton_1e-8", 1, REST_1E8 + ["-sample_input", path])
        start = run(f"rest{n}_newton_1e-8_desaxce", 1, REST_1E8 + ["-sample_input", path, "-solver_newton_desaxce_max_it", "6"])
        if alone is not None and start is not None:
            emit({"bench": "desaxce_start", "disks": int(n), "residual": [float(alone["residual"][0]), float(start["residual"][0])],
                  "newton_steps": [int(alone["iterations"][0]), int(start["iterations"][0])],
                  "desaxce_qps": int(start["desaxce_qps"][0]), "desaxce_seconds": round(float(start["desaxce_seconds"][0]), 3),
                  "solve_seconds": [round(float(alone["solve_seconds"][0]), 3), round(float(start["solve_seconds"][0]), 3)],
                  "order": "newton alone, with the De Saxce start"})

if "ipstart" in parts:
    scenes = {f"rest{n}": REST_1E8 + ["-sample_input", path] for n, path in
              {**rest_samples(), "5000": "cases/compact_5k.h5"}.items()}
    scenes["confine500"] = ["-options_file", "cases/confine500.opts", "-steps", "10"] + NEWTON + ["-solver_tol", "1e-10"]
    # the 500-disk pressure scene of scripts/dem_compare at 5.5 times its dt (2 characteristic times), where two thirds of
    # the contacts within the alert distance stay open, and pressure20k's 5 warm-started steps
    scenes["pressure500_dt5.5e-3"] = pressure_scene(1, 20) + NEWTON + ["-dt", "5.5e-3", "-gap_rule", "predictive", "-solver_tol", "1e-6"]
    scenes["pressure20k"] = pressure_scene(40, 5) + NEWTON + ["-gap_rule", "predictive", "-solver_tol", "1e-8"]
    for name, opts in scenes.items():
        alone = run(f"{name}_newton", 1, opts)
        start = run(f"{name}_newton_ip", 1, opts + IP_START)
        if alone is not None and start is not None:
            emit({"bench": "ip_start", "scene": name, "residual_max": [float(np.max(alone["residual"])), float(np.max(start["residual"]))],
                  "newton_steps": [int(np.sum(alone["iterations"])), int(np.sum(start["iterations"]))],
                  "ip_iterations": int(np.sum(start["ip_iterations"])), "ip_seconds": round(float(np.sum(start["ip_seconds"])), 3),
                  "solve_seconds": [round(float(np.sum(alone["solve_seconds"])), 3), round(float(np.sum(start["solve_seconds"])), 3)],
                  "order": "newton alone, with the interior-point start"})

def emit_ranks_target(bench, one, two, **figures):
    """The line of a one-step 1-against-2-rank comparison: residuals, solve times, speed-up, and the target of 1.7 at
    the same residual (both converged); `figures` adds the part's own counts."""
    t1, t2 = float(one["solve_seconds"][0]), float(two["solve_seconds"][0])
    emit({"bench": bench, "residual_1": float(one["residual"][0]), "residual_2": float(two["residual"][0]), **figures,
          "seconds_1": t1, "seconds_2": t2, "speedup": t1 / t2, "target": "speed-up >= 1.7 at the same residual",
          "met": bool(one["converged"][0] and two["converged"][0] and t1 >= 1.7 * t2)})


if "ranks40k" in parts:
    SQUARE = ["-options_file", "cases/rest_10k.opts", "-sample_input", tiled_sample("cases/compact_10k.h5", 2), "-friction", "0",
              "-output_every", "1000"]
    one = run("square40k_newton_1rank", 1, SQUARE)
    two = run("square40k_newton_2ranks", 2, SQUARE)
    if one is not None and two is not None:
        emit_ranks_target("ranks40k", one, two, newton_steps_1=int(one["iterations"][0]), newton_steps_2=int(two["iterations"][0]))

if "square100k" in parts:
    SQUARE = ["-options_file", "cases/rest_10k.opts", "-sample_input", tiled_sample("cases/compact_5k.h5", 5, 4), "-friction", "0",
              "-output_every", "1000", "-solver_tol", "1e-8", "-solver_newton_ip_max_it", "40"]
    one = run("square100k_newton_ip_1rank", 1, SQUARE)
    two = run("square100k_newton_ip_2ranks", 2, SQUARE)
    if one is not None and two is not None:
        emit_ranks_target("ranks_square100k", one, two, ip_iterations=[int(one["ip_iterations"][0]), int(two["ip_iterations"][0])],
                          newton_steps=[int(one["iterations"][0]), int(two["iterations"][0])])

if "big" in parts:
    s = run("biaxial1M_newton_2ranks", 2, B1M + ["-steps", "1"] + NEWTON + ["-solver_tol", "1e-6"])
    if s is not None:
        grains = 1e6
        emit({"bench": "big", "grains": grains, "residual": float(s["residual"][0]), "seconds": float(s["solve_seconds"][0]),
              "bytes_per_grain": float((s["peak_memory"][0] - s["baseline_memory"][0]) / grains),
              "target": "residual <= 1e-6 within one step", "met": bool(s["residual"][0] <= 1e-6)})

emit({"bench": "files", "dir": tmp})
