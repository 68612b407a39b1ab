#!/usr/bin/python3
"""scripts/tradeoff --quick on confine5: the outputs exist (JSON lines, CSV, work-precision PNGs, summary.md), the
summary names the cheapest setting that meets the target and that setting does meet it and is the cheapest that
does, the reference solves its steps, and every NLGS run with the natural criterion ends its steps below its tolerance.

  check_tradeoff.py --kergs build/kergs --dir WORKDIR
Exit status 0 when every check holds, 1 otherwise."""
import argparse
import csv
import json
import math
import os
import re
import subprocess
import sys
import time

from checks import check, failures

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--kergs", required=True)
    ap.add_argument("--dir", required=True)
    a = ap.parse_args()
    target = 1e-3
    t0 = time.time()
    p = subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "scripts", "tradeoff"), "--quick", "--out", a.dir, "--kergs", a.kergs,
                        "--target", f"wall_force={target:g}"], cwd=ROOT, capture_output=True, text=True)
    took = time.time() - t0
    check(p.returncode == 0, f"tradeoff --quick exits 0 ({p.stderr[-500:]})")
    check(took < 60, f"tradeoff --quick took {took:.1f} s (< 60)")
    check("runs done" in p.stderr and "left" in p.stderr, "a progress line with the time left")
    rows = [json.loads(l) for l in open(os.path.join(a.dir, "tradeoff.jsonl"))]
    grid = [r for r in rows if not r["reference"]]
    ref = [r for r in rows if r["reference"]]
    check(len(ref) == 1 and len(grid) >= 6, f"{len(grid)} settings and one reference in tradeoff.jsonl")
    families = {r["family"].split("/")[0].split(" ")[0] for r in grid}
    check({"nlgs", "nlgsjac", "newton"} <= families, f"the solver families {sorted(families)}")
    check(ref and ref[0]["residual_max"] <= 1e-10 and ref[0]["converged"] == ref[0]["steps"], "the reference solves every step to 1e-10")
    with open(os.path.join(a.dir, "tradeoff.csv")) as f:
        table = list(csv.DictReader(f))
    check(len(table) == len(rows) and "wall_force" in table[0] and "cost" in table[0], "tradeoff.csv has a row per run")
    for e in ("wall_force", "stress", "packing", "energy"):
        png = os.path.join(a.dir, f"wp_{e}.png")
        check(os.path.isfile(png) and open(png, "rb").read(8) == b"\x89PNG\r\n\x1a\n", f"wp_{e}.png is a PNG")
    for r in grid:
        o = r["options"]
        if o["solver"] == "nlgs" and o.get("criterion") == "natural" and r["status"] == 0 and r["converged"] == r["steps"]:
            check(r["residual_max"] <= o["tol"], f"{r['setting']}: worst residual {r['residual_max']:.3g} <= tol")
    text = open(os.path.join(a.dir, "summary.md")).read()
    m = re.search(r"Cheapest setting meeting the target: `([^`]+)`", text)
    check(m is not None, "summary.md names the cheapest setting meeting the target")
    if m:
        named = [r for r in grid if r["setting"] == m.group(1)]
        ok = [r for r in grid if r["status"] == 0 and math.isfinite(r["wall_force"]) and r["wall_force"] <= target]
        check(len(named) == 1 and named[0]["wall_force"] <= target, f"{m.group(1)} meets wall_force <= {target:g}")
        check(named and min(r["cost"] for r in ok) == named[0]["cost"], "and is the cheapest that does")
    print(f"{len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
