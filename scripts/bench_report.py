#!/usr/bin/python3
"""Summarise a kergs results file as one JSON line (used by scripts/bench).

Usage: bench_report.py results.h5 [--label NAME] [--ranks N] [--skip K]
Per-step figures are means over the steps after the first K (default 1: the first step builds caches).
"""
import argparse, json, sys
import h5py
import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("results")
ap.add_argument("--label", default="")
ap.add_argument("--ranks", type=int, default=1)
ap.add_argument("--skip", type=int, default=1)
a = ap.parse_args()

with h5py.File(a.results, "r") as f:
    s = {k: np.asarray(f["stats"][k][()]).ravel() for k in f["stats"].keys()}
    snaps = sorted(f["snapshots"].keys())
    grains = int(np.asarray(f["snapshots"][snaps[-1]]["radius"]).size)
k = slice(min(a.skip, len(s["step"]) - 1), None)
contacts = s["contacts"][k]
sweeps = s["iterations"][k]
sweep_s = s["sweep_seconds"][k]
ns_per_contact_sweep = float(np.sum(sweep_s) / max(np.sum(sweeps * contacts), 1) * 1e9)
out = {
    "bench": a.label or a.results,
    "ranks": a.ranks,
    "grains": grains,
    "steps": int(len(s["step"])),
    "contacts": float(np.mean(contacts)),
    "active": float(np.mean(s["active"][k])),
    "detect_s_per_step": float(np.mean(s["detect_seconds"][k])),
    "assemble_s_per_step": float(np.mean(s["assemble_seconds"][k])),
    "solve_s_per_step": float(np.mean(s["solve_seconds"][k])),
    "io_s_per_step": float(np.mean(s["io_seconds"][k])),
    "sweeps_per_step": float(np.mean(sweeps)),
    "converged_fraction": float(np.mean(s["converged"][k])),
    "ns_per_contact_per_sweep": ns_per_contact_sweep,
    "detect_us_per_grain": float(np.mean(s["detect_seconds"][k]) / grains * 1e6 * a.ranks),
    "peak_memory_bytes_per_grain": float(s["peak_memory"][-1] / grains),
    "peak_memory_above_baseline_bytes_per_grain": float((s["peak_memory"][-1] - s["baseline_memory"][-1]) / grains),
    "mean_violation_last": float(s["mean_violation"][-1]),
    "residual_mean": float(np.mean(s["residual"][k])),
    "nnz_W": float(np.mean(s["nnz_W"][k])) if "nnz_W" in s else None,
}
# kernel-regularised solvers: the projector's factorization, diagonal blocks, prediction
for name in ("factor_seconds", "diag_seconds", "predict_seconds", "nnz_factor", "kernel_dimension", "rank_Hf", "omega"):
    if name in s:
        out[name] = float(np.nanmean(s[name][k]))
if out.get("nnz_factor") and out.get("nnz_W"):
    out["factor_over_nnz_W"] = out["nnz_factor"] / out["nnz_W"]
print(json.dumps(out))
