#!/usr/bin/python3
"""scripts/profiles --quick (docs/profiles.md): exports its problems (--make --quick), runs the quick profile, then checks
the table (one row per problem, solver and accuracy, every field), the PNG, and that every kergs Newton solve reached
1e-8 at the 1e-8 accuracy (and 1e-4 at 1e-4, unless it returned r = 0 at once).

  check_profiles.py --dir WORKDIR [--kergs build/kergs]
Exit status 0 when every check holds, 1 otherwise."""
import argparse
import json
import os
import subprocess
import sys

from checks import check, failures

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PROFILES = os.path.join(ROOT, "scripts", "profiles")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--dir", required=True)
    ap.add_argument("--kergs", default=os.path.join(ROOT, "build", "kergs"))
    a = ap.parse_args()
    problems, out = os.path.join(a.dir, "problems"), os.path.join(a.dir, "out")
    for d in (problems, out):
        if os.path.isdir(d):
            for f in os.listdir(d):
                os.remove(os.path.join(d, f))
    p = subprocess.run([PROFILES, "--make", problems, "--quick", "--kergs", a.kergs], capture_output=True, text=True)
    names = sorted(f for f in os.listdir(problems)) if os.path.isdir(problems) else []
    if not check(p.returncode == 0 and len(names) == 3, f"profiles --make --quick exports 3 problems: {names}"):
        print(p.stdout[-2000:], p.stderr[-2000:])
        return 1
    # 1 s a solve: newton needs milliseconds here; four solves of confine5's step 30 (NLGS, fc2d NSGS and fc3d Newton
    # at 1e-8, fc3d at 1e-4) run to any limit (measured: 5 s each at the default), and their rows check the limit's path
    p = subprocess.run([PROFILES, problems, "--quick", "--time-limit", "1", "--out", out, "--kergs", a.kergs], capture_output=True, text=True)
    print(p.stdout[-4000:])
    check(p.returncode == 0, f"profiles --quick exits 0 (got {p.returncode}){' : ' + p.stderr[-1500:] if p.returncode else ''}")
    table, png = os.path.join(out, "profiles.jsonl"), os.path.join(out, "profiles.png")
    rows = []
    if check(os.path.exists(table), "the table exists"):
        with open(table) as f:
            rows = [json.loads(line) for line in f]
    solvers = {"kergs_newton", "kergs_nlgs", "fc2d_nsgs", "fc3d_nsn_ac"}
    keys = {(r["problem"], r["solver"], r["accuracy"]) for r in rows}
    check(len(rows) == 3 * 4 * 2 and keys == {(n, s, acc) for n in names for s in solvers for acc in (1e-4, 1e-8)},
          f"one row per problem, solver and accuracy: {len(rows)} rows")
    fields = {"problem", "solver", "accuracy", "iterations", "time", "residual", "solved", "status"}
    check(all(fields <= set(r) for r in rows), "every row has " + ", ".join(sorted(fields)))
    check(all(r["time"] > 0 and (not r["solved"] or r["residual"] <= r["accuracy"]) for r in rows),
          "positive times; a solved row reached its accuracy")
    with open(png, "rb") if os.path.exists(png) else open(os.devnull, "rb") as f:
        head = f.read(8)
    check(head == b"\x89PNG\r\n\x1a\n" and os.path.getsize(png) > 5000, "the profile is a PNG")
    newton = [r for r in rows if r["solver"] == "kergs_newton"]
    for r in newton:
        if r["accuracy"] == 1e-8:
            check(r["solved"] and r["residual"] <= 1e-8, f"kergs newton reached 1e-8 on {r['problem']}: residual {r['residual']}")
        else:
            check(r["solved"] or r["status"] == "returned r = 0", f"kergs newton at 1e-4 on {r['problem']}: {r['status']}")
    print(f"{len(failures)} failure(s)" if failures else "every check holds")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
