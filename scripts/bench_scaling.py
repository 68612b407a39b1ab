#!/usr/bin/python3
"""Growth of each phase's cost with the number of grains (the kernel-regularised solvers' benchmarks): runs a solver on hexagonal biaxial packings
of increasing size, prints one JSON line per size with seconds per phase per step, then one line with the
fitted exponents p of t ~ N^p between the smallest and largest size.

Usage: bench_scaling.py [--kergs build/kergs] [--sizes 500,20000,100000] [--solver nlgsjac] [--steps 3] [extra kergs options...]
"""
import argparse, json, math, os, subprocess, sys, tempfile

ap = argparse.ArgumentParser()
ap.add_argument("--kergs", default="build/kergs")
ap.add_argument("--sizes", default="500,20000,100000")
ap.add_argument("--solver", default="nlgsjac")
ap.add_argument("--steps", type=int, default=3)
a, extra = ap.parse_known_args()
env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OPENBLAS_NUM_THREADS="1")
here = os.path.dirname(os.path.abspath(__file__))
tmp = tempfile.mkdtemp(prefix="kergs-scaling.")
r = 0.005
rows = []
for n in [int(x) for x in a.sizes.split(",")]:
    nx = max(2, int(round(math.sqrt(2 * n))))  # a box twice as wide as high
    ny = max(2, n // nx)
    width = 2 * r * nx + r
    height = r + (ny - 1) * math.sqrt(3) * r + r + 1e-6
    path = os.path.join(tmp, f"n{nx * ny}.h5")
    cmd = ["mpiexec", "-n", "1", a.kergs, "-options_file", "cases/jammed_lattice.opts", "-lattice_n", f"{nx},{ny}",
           "-box", f"0,0,{width:.9g},{height:.9g}", "-steps", str(a.steps), "-solver_type", a.solver, "-output", path] + extra
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        sys.exit(f"bench_scaling.py: kergs failed for {nx}x{ny}:\n{p.stdout[-2000:]}{p.stderr[-2000:]}")
    q = subprocess.run(["/usr/bin/python3", os.path.join(here, "bench_report.py"), path, "--label", f"scaling_{a.solver}_{nx * ny}"],
                       capture_output=True, text=True)
    row = json.loads(q.stdout)
    rows.append(row)
    print(json.dumps(row), flush=True)
lo, hi = rows[0], rows[-1]
exps = {"bench": f"scaling_exponents_{a.solver}", "from_grains": lo["grains"], "to_grains": hi["grains"]}
for key in ("detect_s_per_step", "assemble_s_per_step", "solve_s_per_step", "factor_seconds", "diag_seconds", "predict_seconds"):
    if lo.get(key) and hi.get(key) and lo[key] > 0 and hi[key] > 0:
        exps[key] = math.log(hi[key] / lo[key]) / math.log(hi["grains"] / lo["grains"])
print(json.dumps(exps))
