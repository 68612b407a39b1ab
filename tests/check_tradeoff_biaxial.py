#!/usr/bin/python3
"""scripts/tradeoff_biaxial --quick (cases/biaxial_small.opts to 0.06 % strain): the machinery of the biaxial trade.

Every run row holds the macroscopic results (finite peak and critical q/p, the solid fraction of the compacted sample
within 0.01 of its 0.8167, Z above 3); the settings are applied (the paper's capped NLGS never sweeps more than 150
times, the uncapped one does on some step); the reference ran on 1 and 2 ranks and their band is rounding-small (q/p
within 0.02); every setting has a comparison row with an error and a band for each result; the JSON file is complete.
A run killed after a checkpoint (its first 4 steps, no exit status) is continued by --reuse from that checkpoint, to
the uninterrupted run's statistics bit for bit, and the runs that ended are kept as they are. The dilatancy angle of
known strain paths: a steady dilation s = d eps_v / d eps_a gives asin(-s / (2 - s)), and a stretch where the sample
is squeezed from every side (s >= 1, as after a shock) has none: it does not become 90 degrees.

  check_tradeoff_biaxial.py --dir WORKDIR
Exit status 0 when every check holds, 1 otherwise."""
import argparse
import json
import math
import os
import subprocess
import sys

import h5py
import numpy as np

from checks import check, failures

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PHI_SAMPLE, PHI_TOL = 0.8167, 0.01


def results_stats(path):
    """A results file's statistics but the timings and the memory, which no two runs share."""
    with h5py.File(path, "r") as f:
        return {k: f["stats"][k][()] for k in f["stats"] if not (k.endswith("_seconds") or "memory" in k or k == "imbalance")}


def load_script():
    import importlib.machinery
    import importlib.util
    loader = importlib.machinery.SourceFileLoader("tradeoff_biaxial", os.path.join(ROOT, "scripts", "tradeoff_biaxial"))
    spec = importlib.util.spec_from_loader("tradeoff_biaxial", loader)
    tb = importlib.util.module_from_spec(spec)
    loader.exec_module(tb)
    return tb


def check_stop_forwarded(a):
    """A stop request to the script reaches a run under way as SIGUSR1 (here a process that exits 4 on it, as kergs
    does after its checkpoint), and no run starts after it."""
    import threading
    import time
    procs = load_script().Processes()
    waiting = [sys.executable, "-c", "import signal, sys, time\nsignal.signal(signal.SIGUSR1, lambda *a: sys.exit(4))\n"
               "open(sys.argv[1], 'w').close()\ntime.sleep(60)", os.path.join(a.dir, "stop_probe")]
    ready = waiting[-1]
    if os.path.exists(ready):
        os.remove(ready)
    result = {}
    worker = threading.Thread(target=lambda: result.update(code=procs.run(waiting)[0]))
    t0 = time.time()
    worker.start()
    while not os.path.exists(ready) and time.time() - t0 < 30:
        time.sleep(0.05)
    procs.stop(None, None)
    worker.join(60)
    os.remove(ready)
    check(result.get("code") == 4 and time.time() - t0 < 30 and procs.run(["true"])[0] is None,
          "a stop request reaches the run under way as SIGUSR1 (exit %s) and no run starts after it" % result.get("code"))


def check_dilatancy():
    """macroscopic()'s dilatancy on synthetic strain paths."""
    tb = load_script()
    e = np.linspace(0, 0.04, 401)
    base = {"q_over_p": np.full_like(e, 0.3), "solid_fraction": np.full_like(e, 0.8), "Z_nonrattler": np.full_like(e, 3.1)}
    steady = tb.macroscopic(dict(base, strain_axial=e, strain_volumetric=-0.5 * e))
    want = math.degrees(math.asin(0.5 / 2.5))
    check(abs(steady["dilatancy"] - want) < 1e-6, f"steady dilation s = -0.5: psi {steady['dilatancy']:.4f} = {want:.4f} degrees")
    squeezed = -0.5 * e + np.where((e > 0.01) & (e < 0.02), 3.0 * (e - 0.01), np.where(e >= 0.02, 0.03, 0.0))
    shocked = tb.macroscopic(dict(base, strain_axial=e, strain_volumetric=squeezed))
    check(abs(shocked["dilatancy"] - want) < 1e-6, f"with a stretch squeezed at s = 2.5: psi {shocked['dilatancy']:.4f}, the steady "
          "stretches' (it was 90)")


def check_continue(a):
    """The uncapped NLGS run killed after a checkpoint of step 4: tradeoff_biaxial --reuse continues it from there."""
    runs = os.path.join(a.dir, "runs")
    out, kept = os.path.join(runs, "nlgs_quad_1e-4.h5"), os.path.join(runs, "nlgs_paper_150.h5")
    whole, kept_time = results_stats(out), os.path.getmtime(kept)
    cmd = open(out + ".cmd").read().split()
    p = subprocess.run(cmd + ["-steps", "4", "-checkpoint_every", "4", "-checkpoint_path", os.path.join(runs, "nlgs_quad_1e-4.checkpoint.h5")],
                       cwd=ROOT, capture_output=True, text=True)
    os.remove(out + ".cmd.exit")  # killed: no status recorded
    check(p.returncode == 0 and len(results_stats(out)["step"]) == 4, "a run of the first 4 steps and its checkpoint (exit %d)" % p.returncode)
    p = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "tradeoff_biaxial"), "--quick", "--reuse", "--kergs", a.kergs, "--out", a.dir],
                       cwd=ROOT, capture_output=True, text=True)
    if not check(p.returncode == 0, "tradeoff_biaxial --quick --reuse runs (exit %d) %s" % (p.returncode, p.stderr[-500:])):
        return
    row = [json.loads(x) for x in open(os.path.join(a.dir, "tradeoff_biaxial.jsonl")) if '"run": "nlgs_quad_1e-4"' in x][0]
    with h5py.File(out, "r") as f:
        restart_step = f.attrs.get("restart_step")
    check(row.get("continued_from_step") == 4 and restart_step == 4,
          "the killed run continued from its checkpoint: row %s, results file's restart_step %s" % (row.get("continued_from_step"), restart_step))
    again = results_stats(out)
    same = sorted(again) == sorted(whole) and all(np.array_equal(again[k], whole[k], equal_nan=True) for k in whole)
    check(same, "its statistics are the uninterrupted run's, bit for bit: %s differ" %
          [k for k in whole if k not in again or not np.array_equal(again[k], whole[k], equal_nan=True)])
    check(os.path.getmtime(kept) == kept_time, "a run that ended is kept, not run again")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kergs", required=True)
    ap.add_argument("--dir", required=True)
    a = ap.parse_args()
    p = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "tradeoff_biaxial"), "--quick", "--kergs", a.kergs, "--out", a.dir],
                       cwd=ROOT, capture_output=True, text=True)
    if not check(p.returncode == 0, "tradeoff_biaxial --quick runs (exit %d) %s" % (p.returncode, p.stderr[-500:])):
        return 1
    lines = [json.loads(x) for x in open(os.path.join(a.dir, "tradeoff_biaxial.jsonl"))]
    runs = {r["run"]: r for r in lines if "run" in r}
    comps = {c["setting"]: c for c in lines if "run" not in c}
    check(sorted(runs) == ["newton_1e-8_1rank", "newton_1e-8_2ranks", "nlgs_paper_150", "nlgs_quad_1e-4"], "four runs: %s" % sorted(runs))
    for name, r in runs.items():
        check(math.isfinite(r["peak_q"]) and math.isfinite(r["critical_q"]) and abs(r["phi_end"] - PHI_SAMPLE) < PHI_TOL and r["z_end"] > 3,
              "%s: q/p %.3f/%.3f, solid fraction %.4f, Z %.2f" % (name, r["peak_q"], r["critical_q"], r["phi_end"], r["z_end"]))
    check(runs["nlgs_paper_150"]["max_iterations"] <= 150 < runs["nlgs_quad_1e-4"]["max_iterations"],
          "settings applied: capped NLGS %d sweeps at most, uncapped %d" % (runs["nlgs_paper_150"]["max_iterations"],
                                                                           runs["nlgs_quad_1e-4"]["max_iterations"]))
    band = comps["nlgs_paper_150"]["peak_q_band"]
    check(band < 0.02, "the reference's band on peak q/p over 1 and 2 ranks is %.2g, below 0.02" % band)
    check(sorted(comps) == ["newton_1e-8", "nlgs_paper_150", "nlgs_quad_1e-4"] and
          all("critical_q_error" in c and "phi_end_band" in c for c in comps.values()), "a comparison row per setting: %s" % sorted(comps))
    check_continue(a)
    check_stop_forwarded(a)
    check_dilatancy()
    print("%d failure(s)" % len(failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
