#!/usr/bin/python3
"""-solver_monitor, through the executable: for every solver type, on 1 and 2 ranks, the lines written to a file
(-solver_monitor ascii:FILE) agree with the results file: per step, as many lines as the step's `iterations`,
numbered 1, 2, ... in order, times non-decreasing, and the last line's natural residual equal to the step's
recorded `residual`; where a residual is printed before the last line it is the criterion (natural criterion).
Newton's results are the same without the monitor. The energy balance error (law_work_error) follows the accuracy.

  check_monitor.py --kergs build/kergs --mpiexec mpiexec --dir WORKDIR
Exit status 0 when every check holds, 1 otherwise."""
import argparse
import math
import os
import re
import subprocess
import sys

import h5py

from checks import check, failures

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CONFINE5 = os.path.join(ROOT, "cases", "confine5.opts")
LINE = re.compile(r"^step (\d+) iteration (\d+) criterion (\S+) residual (\S+) seconds (\S+)$")


def parse(path):
    steps = {}
    with open(path) as f:
        for line in f:
            m = LINE.match(line.strip())
            if not m:
                check(False, f"{path}: unexpected line {line.strip()!r}")
                continue
            step, it = int(m.group(1)), int(m.group(2))
            res = math.nan if m.group(4) == "-" else float(m.group(4))
            steps.setdefault(step, []).append((it, float(m.group(3)), res, float(m.group(5))))
    return steps


def one(a, ranks, stype, extra, tag):
    tag = f"{tag}_{ranks}"
    mon = os.path.join(a.dir, tag + ".monitor")
    out = os.path.join(a.dir, tag + ".h5")
    cmd = [a.mpiexec, "-n", str(ranks), a.kergs, "-options_file", CONFINE5, "-steps", "12", "-solver_type", stype,
           "-solver_monitor", "ascii:" + mon, "-output", out, "-quiet"] + extra
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    check(p.returncode == 0, f"{tag}: kergs exits 0 ({p.stderr[-300:]})")
    if p.returncode:
        return None
    with h5py.File(out, "r") as f:
        iters, resid, step = f["stats/iterations"][()], f["stats/residual"][()], f["stats/step"][()]
    lines = parse(mon)
    check(sum(len(v) for v in lines.values()) == int(iters.sum()) and iters.sum() > 0,
          f"{tag}: {sum(len(v) for v in lines.values())} monitor lines for {int(iters.sum())} iterations")
    for k, s in enumerate(step.astype(int)):
        got = lines.get(s, [])
        if len(got) != int(iters[k]):
            check(False, f"{tag} step {s}: {len(got)} lines, {int(iters[k])} iterations")
            continue
        if not got:
            continue
        ok = [g[0] for g in got] == list(range(1, len(got) + 1)) and all(
            got[i][3] <= got[i + 1][3] for i in range(len(got) - 1))
        ok = ok and abs(got[-1][2] - resid[k]) <= 1e-9 * abs(resid[k]) + 1e-300
        if not ok:
            check(False, f"{tag} step {s}: lines {got[:3]}... last residual {got[-1][2]!r} recorded {resid[k]!r}")
            return None
    check(True, f"{tag}: every step's lines match its iterations and recorded residual")
    return lines, out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--kergs", required=True)
    ap.add_argument("--mpiexec", default="mpiexec")
    ap.add_argument("--dir", required=True)
    a = ap.parse_args()
    a.kergs = os.path.abspath(a.kergs)
    os.makedirs(a.dir, exist_ok=True)
    got = {}
    for ranks in (1, 2):
        got["quad", ranks] = one(a, ranks, "nlgs", [], "nlgs")
        got["natural", ranks] = one(a, ranks, "nlgs", ["-solver_criterion", "natural"], "nlgs_natural")
        one(a, ranks, "nlgsjac", ["-predictor_type", "linear"], "nlgsjac")
        one(a, ranks, "nlkergs", [], "nlkergs")
        got["newton", ranks] = one(a, ranks, "newton", ["-solver_tol", "1e-10"], "newton")
    if got["quad", 1] and got["natural", 1]:
        q, n = got["quad", 1][0], got["natural", 1][0]
        check(all(math.isnan(r[2]) for v in q.values() for r in v[:-1]), "quad criterion: no residual before the last line")
        check(all(r[2] == r[1] for v in n.values() for r in v[:-1]), "natural criterion: the residual is the criterion")
    # the energy balance error (law_work_error over contact_energy) follows the accuracy, on the 4 steps before confine5
    # jams: below 1e-8 for newton to 1e-10, of the order of the residual (1e-5) for NLGS to 1e-6, above 1e-3 for NLGS-Jac
    ratios = {}
    for tag in ("newton_1", "nlgs_natural_1", "nlgsjac_1"):
        with h5py.File(os.path.join(a.dir, tag + ".h5"), "r") as f:
            ratios[tag] = f["stats/law_work_error"][:4] / f["stats/contact_energy"][:4]
    check(max(ratios["newton_1"]) < 1e-8, f"newton 1e-10: energy balance error {max(ratios['newton_1']):.2g} < 1e-8")
    check(1e-9 < max(ratios["nlgs_natural_1"]) < 1e-4, f"nlgs natural 1e-6: energy balance error {max(ratios['nlgs_natural_1']):.2g}")
    check(min(ratios["nlgsjac_1"]) > 1e-3, f"nlgsjac: energy balance error at least {min(ratios['nlgsjac_1']):.2g} > 1e-3")
    if got["newton", 1]:  # the monitor computes residuals Newton would not: the results must not change
        out = os.path.join(a.dir, "newton_nomonitor.h5")
        p = subprocess.run([a.kergs, "-options_file", CONFINE5, "-steps", "12", "-solver_type", "newton", "-solver_tol", "1e-10",
                            "-output", out, "-quiet"], cwd=ROOT, capture_output=True, text=True)
        with h5py.File(out, "r") as f, h5py.File(got["newton", 1][1], "r") as g:
            same = all((f["stats/" + k][()] == g["stats/" + k][()]).all() for k in ("residual", "iterations", "max_violation"))
        check(p.returncode == 0 and same, "newton: the same residuals, iterations and interpenetrations without the monitor")
    print(f"{len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
