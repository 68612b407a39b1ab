#!/usr/bin/python3
"""Reproduce the paper's Figures 2 and 3 on the confine5 scene: sweeps per step and mean violation over 40 steps
for NLGS, NLKerGS-P with the linear predictor, and with the elastic predictor for two epsilon.

Usage: scripts/paper_figures.py [--kergs build/kergs] [--out results/paper_figures] [--solver nlkergs|nlgsjac]
Writes <out>/figure2_3.png (two panels, like the paper's a and b), <out>/figure2_3.md (table) and prints one
JSON line per variant (total sweeps, steps at the cap, final mean violation, largest violation).
"""
import argparse, json, os, subprocess, sys
import h5py
import numpy as np
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

ap = argparse.ArgumentParser()
ap.add_argument("--kergs", default="build/kergs")
ap.add_argument("--out", default="results/paper_figures")
ap.add_argument("--solver", default="nlkergs", help="regularised solver type used for the predictor variants")
ap.add_argument("--case", default="cases/confine5.opts")
ap.add_argument("--eta", default="1e-8")
ap.add_argument("--epsilons", default="1e-2,1e-6")
a = ap.parse_args()
os.makedirs(a.out, exist_ok=True)
env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OPENBLAS_NUM_THREADS="1")

variants = [("NLGS", ["-solver_type", "nlgs"]),
            ("linear predictor", ["-solver_type", a.solver, "-predictor_type", "linear", "-predictor_eta", a.eta])]
for eps in a.epsilons.split(","):
    variants.append((f"elastic, eps={eps}", ["-solver_type", a.solver, "-predictor_type", "elastic", "-predictor_epsilon", eps]))

def run(label, opts):
    path = os.path.join(a.out, label.replace(" ", "_").replace(",", "").replace("=", "") + ".h5")
    cmd = ["mpiexec", "-n", "1", a.kergs, "-options_file", a.case, "-output", path, "-quiet"] + opts
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        sys.exit(f"paper_figures.py: kergs failed for {label}:\n{p.stdout[-2000:]}{p.stderr[-2000:]}")
    with h5py.File(path, "r") as f:
        return {k: np.asarray(f["stats"][k][()]).ravel() for k in f["stats"].keys()}

results = {label: run(label, opts) for label, opts in variants}
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
rows = []
for label, s in results.items():
    ax1.plot(s["step"], s["iterations"], marker="o", ms=3, label=label)
    ax2.plot(s["step"], s["mean_violation"], marker="o", ms=3, label=label)
    cap = int(np.max(s["iterations"]))
    row = {"variant": label, "total_sweeps": int(np.sum(s["iterations"])), "steps_at_cap": int(np.sum(s["converged_reason"][()] == -1)),
           "final_mean_violation": float(s["mean_violation"][-1]), "largest_violation": float(np.max(s["max_violation"]))}
    rows.append(row)
    print(json.dumps({"bench": "paper_figure_2_3", **row}))
ax1.set_xlabel("step"); ax1.set_ylabel("sweeps"); ax1.set_title("(a) sweeps per step (cap 150)")
ax2.set_xlabel("step"); ax2.set_ylabel("mean violation (m)"); ax2.set_title("(b) mean interpenetration")
ax1.legend(fontsize=8); ax2.legend(fontsize=8)
fig.suptitle("confine5: the paper's Figures 2 and 3")
fig.tight_layout()
png = os.path.join(a.out, "figure2_3.png")
fig.savefig(png + ".tmp.png", dpi=120); os.replace(png + ".tmp.png", png)
md = os.path.join(a.out, "figure2_3.md")
with open(md + ".tmp", "w") as f:
    f.write("| variant | total sweeps (40 steps) | steps at the cap | final mean violation | largest violation |\n|---|---|---|---|---|\n")
    for r in rows:
        f.write(f"| {r['variant']} | {r['total_sweeps']} | {r['steps_at_cap']} | {r['final_mean_violation']:.3e} | {r['largest_violation']:.3e} |\n")
os.replace(md + ".tmp", md)
print(json.dumps({"bench": "paper_figure_2_3_files", "png": png, "table": md}))
