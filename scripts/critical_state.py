#!/usr/bin/python3
"""The critical state does not depend on the initial density: a dense and a loose sample, sheared alike, end at the same
q/p and solid fraction, within the scatter. Too long for the test suite (about 20 % axial strain); its measured result
is in docs/results.md ("Checks of the biaxial test").

The dense sample is cases/compact_small.opts compacted frictionless, the loose one the same grains compacted at
mu = 0.5 (both to rest, NLGS to quad 1e-4); both are sheared by cases/biaxial_small.opts (mu = 0.5, lateral walls under
sigma3 = 1) at the inertial number --inertial to --strain axial strain, with the top and bottom walls made infinite
lines (the box's walls are segments of the initial box: the sample widens beyond them at large strain and grains
escape through the corners). The two runs go in parallel, one rank each.

  critical_state.py --kergs build/kergs [--n 300 --box 0.73 --inertial 2e-3 --strain 0.2 --dir results/critical_state]

One JSON object a line: per sample and per --window of axial strain, the means of q/p and of the solid fraction
("kind": "window"); per sample, the means and standard deviations over the last --last of the strain ("kind": "end");
then the comparison ("kind": "compare": the differences of the end means against the larger standard deviation)."""
import argparse
import concurrent.futures
import json
import os
import subprocess
import sys

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
D_MEAN = 0.0312  # mean diameter of compact_small's grains (radii 0.01-0.02 m, area law), m
DT = 2e-3  # cases/biaxial_small.opts' -dt
NLGS = ["-solver_type", "nlgs", "-solver_criterion", "quad", "-solver_tol", "1e-4", "-solver_max_it", "1000"]


def run(a, args, log):
    with open(os.path.join(a.dir, log), "w") as f:
        p = subprocess.run([a.mpiexec, "-n", "1", os.path.abspath(a.kergs)] + [str(x) for x in args], cwd=ROOT, stdout=f,
                           stderr=subprocess.STDOUT)
    if p.returncode != 0:
        sys.exit("kergs failed (exit %d), see %s" % (p.returncode, os.path.join(a.dir, log)))


def sample_box(path):
    """The box the compaction's walls stopped in, which the sample records (the shear starts in it: -box_from_sample)."""
    with h5py.File(path, "r") as f:
        return f["sample/box"][()].ravel()


def pipeline(a, name, mu):
    """Compact at friction mu, then shear at mu = 0.5; returns the shear's /stats path."""
    sample, out = os.path.join(a.dir, name + ".sample.h5"), os.path.join(a.dir, name + ".h5")
    box = "0,0,%g,%g" % (a.box, a.box)
    run(a, ["-options_file", "cases/compact_small.opts", "-friction", mu, "-random_n", a.n, "-random_box", box, "-box", box, *NLGS,
            "-output", os.path.join(a.dir, name + ".compact.h5"), "-sample_output", sample], name + ".compact.log")
    b = sample_box(sample)
    speed = a.inertial / D_MEAN * (b[3] - b[1])  # I = eps_dot d sqrt(rho / sigma3), rho = sigma3 = 1
    steps = int(round(a.strain / (a.inertial / D_MEAN) / DT))
    run(a, ["-options_file", "cases/biaxial_small.opts", "-sample_input", sample,
            "-wall_box_top_velocity", "0,%g" % -speed, "-wall_box_top_infinite", "-wall_box_bottom_infinite", "-steps", steps,
            "-output", out, "-output_every", 100], name + ".shear.log")
    return out


def summarise(a, name, path):
    with h5py.File(path, "r") as f:
        s = f["stats"]
        eps, q, phi = s["strain_axial"][()], s["q_over_p"][()], s["solid_fraction"][()]
    lines = []
    for lo in np.arange(0, eps[-1], a.window):
        m = (eps >= lo) & (eps < lo + a.window)
        lines.append({"kind": "window", "sample": name, "strain": [round(lo, 4), round(lo + a.window, 4)],
                      "q_over_p": round(float(q[m].mean()), 4), "solid_fraction": round(float(phi[m].mean()), 4)})
    m = eps >= (1 - a.last) * eps[-1]
    end = {"kind": "end", "sample": name, "solid_fraction_start": round(float(phi[0]), 4), "strain_end": round(float(eps[-1]), 4),
           "q_over_p": round(float(q[m].mean()), 4), "q_over_p_std": round(float(q[m].std()), 4),
           "solid_fraction": round(float(phi[m].mean()), 4), "solid_fraction_std": round(float(phi[m].std()), 4)}
    return lines, end


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kergs", default="build/kergs")
    ap.add_argument("--mpiexec", default="mpiexec")
    ap.add_argument("--dir", default="results/critical_state")
    ap.add_argument("--n", type=int, default=300, help="grains (-random_n)")
    ap.add_argument("--box", type=float, default=0.73, help="side of the compaction's square box, m (0.73 for 300 grains)")
    ap.add_argument("--inertial", type=float, default=2e-3, help="inertial number of the shear")
    ap.add_argument("--strain", type=float, default=0.2, help="axial strain at the end of the shear")
    ap.add_argument("--window", type=float, default=0.02, help="strain window of the profile lines")
    ap.add_argument("--last", type=float, default=0.25, help="fraction of the strain over which the end state is averaged")
    a = ap.parse_args()
    os.makedirs(a.dir, exist_ok=True)
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
        jobs = {name: pool.submit(pipeline, a, name, mu) for name, mu in (("dense", 0), ("loose", 0.5))}
        paths = {name: job.result() for name, job in jobs.items()}
    ends = {}
    for name, path in paths.items():
        lines, ends[name] = summarise(a, name, path)
        for line in lines + [ends[name]]:
            print(json.dumps(line), flush=True)
    d, l = ends["dense"], ends["loose"]
    print(json.dumps({"kind": "compare", "grains": a.n, "inertial": a.inertial, "strain": a.strain,
                      "start_solid_fraction_gap": round(d["solid_fraction_start"] - l["solid_fraction_start"], 4),
                      "q_over_p_gap": round(d["q_over_p"] - l["q_over_p"], 4),
                      "q_over_p_scatter": max(d["q_over_p_std"], l["q_over_p_std"]),
                      "solid_fraction_gap": round(d["solid_fraction"] - l["solid_fraction"], 4),
                      "solid_fraction_scatter": max(d["solid_fraction_std"], l["solid_fraction_std"])}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
