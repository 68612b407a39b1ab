#!/usr/bin/python3
"""Speed-up of the distributed engine: runs the biaxial case at each size on 1 and on N ranks with plain
NLGS to the same criterion, and prints one JSON line per run (seconds per phase per step, sweeps, residual, bytes
sent, ghosts, edge cut) and one comparison line per size: whole-step speed-up, extra sweeps caused by the
cross-rank Jacobi coupling, bytes exchanged per step and per sweep.

Per-step figures are means over the steps after the first (the first builds the initial partition and caches).
The partition balances each rank's measured time in the sweeps (-partition_work measured) and is checked at every
step (-partition_check_every 1), so that METIS replaces the initial geometric partition after the first step and
follows the active set as it spreads, as it would in the steady state of a long run; on one rank they do nothing.
The first steps of the compression are a transient (the active set grows from the walls; the partition follows one
step late): 100,000 grains run 8 steps by default (with 4, the 2-rank step was 1.62x faster instead of 1.91x).
The runs are sequential so that they do not share cores.

The sweep count of a step varies by +-10 % with the partition's Jacobi coupling and the packing's evolution, in
both directions, so the comparison also gives the speed-up per sweep, which does not depend on it.

Usage: bench_ranks.py [--kergs build/kergs] [--sizes 20000,100000] [--ranks 2] [--steps 10,8] [--tol 1e-4] [--max-it 6000]
"""
import argparse, json, os, subprocess, sys, tempfile
import h5py
import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("--kergs", default="build/kergs")
ap.add_argument("--sizes", default="20000,100000")
ap.add_argument("--ranks", type=int, default=2)
ap.add_argument("--steps", default="10,8", help="steps per size (one value, or one per size)")
ap.add_argument("--tol", type=float, default=1e-4)
ap.add_argument("--max-it", type=int, default=6000)
a = ap.parse_args()
env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OPENBLAS_NUM_THREADS="1",
           OMPI_MCA_rmaps_base_oversubscribe="1")
tmp = tempfile.mkdtemp(prefix="kergs-ranks.")
# the biaxial case at 20,000 disks (cases/jammed_lattice.opts) and its 100,000-disk version of scripts/bench
SIZES = {20000: [], 100000: ["-lattice_n", "400,250", "-box", "0,0,4.005,2.17009", "-alert", "5e-4"]}
PHASES = ("step_seconds", "detect_seconds", "assemble_seconds", "solve_seconds", "sweep_seconds")


def run(size, ranks, steps):
    path = os.path.join(tmp, f"biaxial{size}_{ranks}.h5")
    cmd = ["mpiexec", "-n", str(ranks), a.kergs, "-options_file", "cases/jammed_lattice.opts", *SIZES[size], "-steps", str(steps),
           "-solver_type", "nlgs", "-solver_criterion", "quad", "-solver_tol", str(a.tol), "-solver_max_it", str(a.max_it),
           "-partition_work", "measured", "-partition_check_every", "1", "-output", path, "-quiet"]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        sys.exit(f"bench_ranks.py: kergs failed on {ranks} rank(s), {size} disks:\n{p.stdout[-2000:]}{p.stderr[-2000:]}")
    with h5py.File(path, "r") as f:
        s = {k: np.asarray(f["stats"][k][()]).ravel()[1:] for k in f["stats"].keys()}
    row = {"bench": f"ranks_biaxial{size}", "ranks": ranks, "grains": size, "steps_measured": int(len(s["step"])),
           "contacts": float(np.mean(s["contacts"])), "sweeps_per_step": float(np.mean(s["iterations"])),
           "converged_fraction": float(np.mean(s["converged"])), "residual_mean": float(np.mean(s["residual"])),
           "sent_bytes_per_step": float(np.mean(s["sent_bytes"])), "ghosts": float(np.mean(s["ghosts"])),
           "edge_cut": float(np.mean(s["edge_cut"])), "imbalance": float(np.mean(s["imbalance"]))}
    for name in PHASES:
        row[name.replace("_seconds", "_s_per_step")] = float(np.mean(s[name]))
    print(json.dumps(row), flush=True)
    return row


sizes = [int(x) for x in a.sizes.split(",")]
steps = [int(x) for x in a.steps.split(",")]
for i, size in enumerate(sizes):
    if size not in SIZES:
        sys.exit(f"bench_ranks.py: no biaxial set-up for {size} disks (known: {sorted(SIZES)})")
    nsteps = steps[min(i, len(steps) - 1)]
    one, many = run(size, 1, nsteps), run(size, a.ranks, nsteps)
    cmp = {"bench": f"ranks_biaxial{size}_speedup", "ranks": a.ranks, "grains": size,
           "speedup_step": one["step_s_per_step"] / many["step_s_per_step"],
           "speedup_detect": one["detect_s_per_step"] / max(many["detect_s_per_step"], 1e-12),
           "speedup_assemble": one["assemble_s_per_step"] / max(many["assemble_s_per_step"], 1e-12),
           "speedup_solve": one["solve_s_per_step"] / many["solve_s_per_step"],
           "speedup_per_sweep": (one["sweep_s_per_step"] / one["sweeps_per_step"]) / (many["sweep_s_per_step"] / many["sweeps_per_step"]),
           "extra_sweeps_fraction": many["sweeps_per_step"] / one["sweeps_per_step"] - 1.0,
           "residual_1": one["residual_mean"], f"residual_{a.ranks}": many["residual_mean"],
           "sent_bytes_per_step": many["sent_bytes_per_step"],
           "sent_bytes_per_sweep": many["sent_bytes_per_step"] / max(many["sweeps_per_step"], 1.0),
           "both_converged": bool(one["converged_fraction"] == 1.0 and many["converged_fraction"] == 1.0)}
    print(json.dumps(cmp), flush=True)
