#!/usr/bin/python3
"""scripts/tradeoff_biaxial --quick (cases/biaxial_small.opts to 0.06 % strain): the machinery of the biaxial trade.

Every run row holds the macroscopic results (finite peak and critical q/p, the solid fraction of the compacted sample
within 0.01 of its 0.8167, Z above 3); the settings are applied (the paper's capped NLGS never sweeps more than 150
times, the uncapped one does on some step); the reference ran on 1 and 2 ranks and their band is rounding-small (q/p
within 0.02); every setting has a comparison row with an error and a band for each result; the JSON file is complete.

  check_tradeoff_biaxial.py --dir WORKDIR
Exit status 0 when every check holds, 1 otherwise."""
import argparse
import json
import math
import os
import subprocess
import sys

from checks import check, failures

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PHI_SAMPLE, PHI_TOL = 0.8167, 0.01


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
    print("%d failure(s)" % len(failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
