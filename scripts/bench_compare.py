#!/usr/bin/python3
"""kergs NLGS against Siconos fc2d NSGS on the same exported FCLib problem (used by scripts/bench).

Usage: bench_compare.py results.h5 problem.fclib.h5 --step K [--label NAME] [--sweeps N]
kergs's time per sweep comes from the results file (sweep_seconds / iterations of step K, the exported
step); Siconos runs exactly the same number of sweeps (at least 20) on the exported problem, sparse block
storage. Prints one JSON line with both times per sweep and their ratio (> 1: kergs faster).
"""
import argparse, json, os, subprocess, sys
import h5py
import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("results")
ap.add_argument("problem")
ap.add_argument("--step", type=int, required=True)
ap.add_argument("--label", default="")
ap.add_argument("--sweeps", type=int, default=0)
a = ap.parse_args()

with h5py.File(a.results, "r") as f:
    s = {k: np.asarray(f["stats"][k][()]).ravel() for k in f["stats"].keys()}
row = a.step - 1  # -fclib_step K exports the solve of the step whose line says "step K", recorded in stats row K - 1
kergs_sweeps = int(s["iterations"][row])
kergs_sps = float(s["sweep_seconds"][row]) / max(kergs_sweeps, 1)
sweeps = a.sweeps or max(kergs_sweeps, 20)
here = os.path.dirname(os.path.abspath(__file__))
p = subprocess.run(["/usr/bin/python3", os.path.join(here, "siconos_solve.py"), a.problem, "--fixed-sweeps", str(sweeps), "--json"],
                   capture_output=True, text=True)
if p.returncode != 0:
    print(json.dumps({"bench": a.label, "error": "siconos_solve.py failed", "stderr": p.stderr[-500:]}))
    sys.exit(1)
sic = json.loads(p.stdout.strip().splitlines()[-1])
out = {
    "bench": "nlgs_vs_siconos_" + (a.label or os.path.basename(a.problem)),
    "contacts_exported": sic.get("contacts"),
    "contacts_kergs": float(s["contacts"][row]),
    "kergs_sweeps": kergs_sweeps,
    "kergs_seconds_per_sweep": kergs_sps,
    "siconos_sweeps": sic.get("iterations"),
    "siconos_seconds_per_sweep": sic.get("seconds_per_sweep"),
    "siconos_storage": sic.get("storage"),
    "ratio_siconos_over_kergs": (sic["seconds_per_sweep"] / kergs_sps) if sic.get("seconds_per_sweep") and kergs_sps > 0 else None,
    "residual_kergs": sic.get("residual_kergs"),
}
print(json.dumps(out))
