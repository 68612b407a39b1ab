#!/usr/bin/python3
"""The quick biaxial workflow through the executable, on one rank: cases/compact_small.opts then cases/biaxial_small.opts.

1. compaction: the run ends at rest (its own -stop_at_rest), the radii follow the area law (r^2 uniform: its mean is
   (rmin^2 + rmax^2)/2 within 3 standard errors), the solid fraction lies in [0.80, 0.83] (measured 0.8167: 300
   frictionless disks of size ratio 2; the loose start is 0.445), and the Love-Weber stress from the contacts equals
   the walls' pressure p in both directions to 1 % (measured 0.2 %), and the sample records its box (/sample/box, where
   the free walls stopped) as its grains' hull to 1e-5 (measured 1e-10), which biaxial_small takes by -box_from_sample;
2. biaxial: q/p, 0 at the end of the isotropic compaction (below 0.05, measured 0.015), stays above 0.2 over the run (measured 0.30 to
   0.37), and strain_axial equals the top wall's travel (from the snapshots' walls) over the initial height to 1e-6.

  check_biaxial.py --kergs build/kergs --mpiexec mpiexec --dir WORKDIR
Exit status 0 when every check holds, 1 otherwise."""
import argparse
import os
import sys

import h5py
import numpy as np

from checks import Kergs, check, failures

P = 1.0  # -wall_box_<side>_pressure of cases/compact_small.opts
RMIN, RMAX = 0.01, 0.02  # its -random_radius
PHI_BAND = (0.80, 0.83)
STRESS_TOL = 0.01
Q_ISOTROPIC, Q_SHEARED = 0.05, 0.2
STRAIN_TOL = 1e-6
BOX_TOL = 1e-5  # the walls at rest against the outermost grains (measured 1e-8)


def compaction(k):
    out, sample = k.path("compact.h5"), k.path("sample.h5")
    p = k.run(1, "-options_file", "cases/compact_small.opts", "-output", out, "-sample_output", sample, log="compact.log")
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
    return sample, q


def biaxial(k, sample, q0):
    out = k.path("biaxial.h5")
    p = k.run(1, "-options_file", "cases/biaxial_small.opts", "-sample_input", sample, "-output", out, log="biaxial.log")
    if not check(p.returncode == 0, "biaxial runs (exit %d)" % p.returncode):
        return
    f = h5py.File(out, "r")
    s, snaps = f["stats"], f["snapshots"]
    q = s["q_over_p"][()]
    check(q.min() > Q_SHEARED > q0, "q/p rises from %.4f to [%.3f, %.3f], above %g" % (q0, q.min(), q.max(), Q_SHEARED))
    steps, eps = s["step"][()], s["strain_axial"][()]
    first = snaps[sorted(snaps.keys())[0]]["walls"][()]
    h0 = first[2, 1] - first[0, 1]  # walls: bottom, right, top, left
    worst = 0.0
    for key in sorted(snaps.keys())[1:]:
        g = snaps[key]
        w = g["walls"][()]
        travel = (h0 - (w[2, 1] - w[0, 1])) / h0
        row = np.flatnonzero(steps == g.attrs["step"])[0]
        worst = max(worst, abs(eps[row] - travel))
    check(worst < STRAIN_TOL and eps[-1] > 0.015, "strain_axial (last %.5f) is the top wall's travel over H0 to %.1e" % (eps[-1], worst))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kergs", required=True)
    ap.add_argument("--mpiexec", required=True)
    ap.add_argument("--dir", required=True)
    k = Kergs(ap.parse_args())
    os.makedirs(k.dir, exist_ok=True)
    got = compaction(k)
    if got:
        biaxial(k, *got)
    print("%d failure(s)" % len(failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
