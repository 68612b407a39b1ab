#!/usr/bin/python3
"""scripts/dem_compare --quick: both codes ran (a kergs row and a LAMMPS row), every row has the reported fields with
finite values, both force histories grow as the walls advance, they agree within a factor 10 on every interval after
the first (the order of magnitude: in the first the walls have barely touched), LAMMPS's largest overlap is within a
factor 2 of its target (kn is chosen from kergs's contact force for that), the force history figure is written.

With --scene pressure (scripts/dem_compare --scene pressure --quick: the deposit pushed by a free wall under a constant
force, a problem with a rigid answer): both codes ran, the fields are there and finite, the wall moves in at every
interval in both, kergs's `newton` converged on every step and added no interpenetration beyond the deposit's own
(0.45 % of d) plus 0.1 % of d, LAMMPS's overlap (level 0.03 %) is at most 3 times its target, the two wall
histories agree within 10 % of LAMMPS's travel on every interval after the first, the figure pressure.png is
written.

With --scene biaxial (scripts/dem_compare --scene biaxial --quick: compact_small's sample sheared to 0.3 % axial
strain, kergs with the case's nlgs, LAMMPS at 0.01 % overlap): both codes ran, the curves are at the same axial
strains (every 0.05 %) and finite, LAMMPS's mean overlap at sigma3 after its isotropic stage is within a factor 2 of
its target (k_n = sigma3 / level), the lateral walls' stress is sigma3 within 5 % in both codes (the mean over the
curve after its first point: pressure times the current wall length), and LAMMPS's q/p agrees with kergs's within
0.08 at every point from 0.1 % axial strain (measured: 0.05 at most; the first point, 0.05 % of strain, is the soft
contacts' elastic mobilisation, 0.24 against 0.46), the figure biaxial.png is written; and, without a run, the
friction read from the biaxial cases, the macroscopic results read from curves of known peak, critical state and
dilatancy, and the band arithmetic of --band on two results files written here.

  check_dem_compare.py --kergs build/kergs --dir WORKDIR [--scene pressure|biaxial]
Exit status 0 when every check holds, 1 otherwise."""
import argparse
import json
import math
import os
import subprocess
import sys
import time
import types

from checks import check, failures

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FIELDS = ["code", "setting", "dt", "steps", "wall_seconds", "seconds_per_tc", "forces", "packing", "overlap_max"]


PRESSURE_FIELDS = ["code", "setting", "dt", "steps", "wall_seconds", "seconds_per_tc", "history", "travel", "packing",
                   "overlap_max"]


def run_and_read(a, scene, jsonl, png, figure, fields, series, keys):
    """scripts/dem_compare --quick (with --scene SCENE unless None) and the checks every scene shares: exit status, time,
    the JSON lines file, a kergs and a LAMMPS run, the summary, the figure PNG, every field present and finite (the
    per-interval list SERIES with its KEYS included). Returns the kergs rows and the LAMMPS rows."""
    name = "dem_compare" + (f" --scene {scene}" if scene else "") + " --quick"
    t0 = time.time()
    p = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "dem_compare")] + (["--scene", scene] if scene else []) +
                       ["--quick", "--kergs", a.kergs, "--out", a.dir], capture_output=True, text=True)
    wall = time.time() - t0
    check(p.returncode == 0, f"{name} exits 0 (status {p.returncode}) {p.stderr[-1500:]}")
    print(f"{name}: {wall:.1f} s (not checked: timings belong in benchmarks, a loaded machine doubles them)")
    rows = [json.loads(l) for l in p.stdout.splitlines() if l.strip()]
    with open(os.path.join(a.dir, jsonl)) as f:
        check([json.loads(l) for l in f] == rows, f"{jsonl} holds the printed lines")
    runs = [r for r in rows if "code" in r]
    kergs = [r for r in runs if r["code"] == "kergs"]
    lmp = [r for r in runs if r["code"] == "lammps"]
    check(len(kergs) >= 1 and len(lmp) >= 1, f"a kergs run and a LAMMPS run ({len(kergs)}, {len(lmp)})")
    check(bool(rows) and "summary" in rows[-1], "the last line is the summary")
    path = os.path.join(a.dir, png)
    with open(path, "rb") if os.path.exists(path) else open(os.devnull, "rb") as f:
        check(f.read(8) == b"\x89PNG\r\n\x1a\n", f"the {figure} figure {png} is a PNG")
    for r in runs:
        miss = [k for k in fields if k not in r]
        check(not miss, f"{r.get('code')} {r.get('setting')}: fields present (missing {miss})")
        nums = [r[k] for k in fields[2:] if k != series and k in r]
        nums += [h[k] for h in r.get(series, []) for k in keys]
        check(all(math.isfinite(v) for v in nums), f"{r.get('code')} {r.get('setting')}: finite values")
    return kergs, lmp


def check_pressure(a):
    kergs, lmp = run_and_read(a, "pressure", "dem_compare_pressure.jsonl", "pressure.png", "wall history", PRESSURE_FIELDS,
                              "history", ("time", "wall_x", "right_x"))
    for r in kergs + lmp:
        check(0.7 < r["packing"] < 0.85, f"{r['code']}: packing fraction of the deposit ({r['packing']:.4f})")
        x = [h["wall_x"] for h in r["history"]]
        check(len(x) == 5 and all(b < a_ for a_, b in zip(x, x[1:])) and x[0] < 0.5 and r["travel"] > 0,
              f"{r['code']}: the free wall moves in at every interval ({x})")
    if kergs and lmp:
        k, l = kergs[0], lmp[0]
        check(k["converged_steps"] == k["steps"], f"kergs newton converged on every step ({k['converged_steps']} of {k['steps']})")
        check(k["overlap_max"] < 0.0046 + 0.001, f"kergs adds no interpenetration beyond the deposit's own ({k['overlap_max']:.2e} of d)")
        check(l["overlap_max"] < 3 * l["overlap_target"], f"LAMMPS overlap {l['overlap_max']:.2e} near its target {l['overlap_target']:.0e}")
        check([round(h["time"], 9) for h in k["history"]] == [round(h["time"], 9) for h in l["history"]],
              "the wall histories are at the same times")
        err = max(abs(p_["wall_x"] - q["wall_x"]) for p_, q in list(zip(k["history"], l["history"]))[1:]) / l["travel"]
        check(err < 0.1, f"kergs's and LAMMPS's wall positions agree within 10 % of the travel (worst {100 * err:.1f} %)")
    print("check_dem_compare --scene pressure: " + ("all checks hold" if not failures else f"{len(failures)} failed"))
    return 1 if failures else 0


BIAXIAL_FIELDS = ["code", "setting", "dt", "steps", "wall_seconds", "seconds_per_percent", "strain_axial", "q_over_p",
                  "strain_volumetric", "solid_fraction", "Z", "sxx", "syy"]
SIGMA3 = 1.0  # cases/biaxial_small.opts's lateral pressure
SXX_TOL = 0.05
QP_TOL, QP_FROM = 0.08, 0.001


def load_script():
    """scripts/dem_compare as a module (it has no .py suffix), for the checks of its reading functions."""
    import importlib.machinery
    import importlib.util
    loader = importlib.machinery.SourceFileLoader("dem_compare", os.path.join(ROOT, "scripts", "dem_compare"))
    spec = importlib.util.spec_from_loader("dem_compare", loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def case_refusal(dc, folder, name, lines):
    """dem_compare's refusal of a case made of `lines` (its message), or "" when it accepts the case."""
    path = os.path.join(folder, name)
    with open(path, "w") as f:
        f.write("".join(lines))
    try:
        dc.check_case(dc.case_options(path), path)
    except SystemExit as e:
        return str(e)
    return ""


def check_biaxial_reading(a):
    """Without a run: the friction read from a case (kergs's rule: -friction, then -friction_pairs), the macroscopic
    results read from curves of known peak, critical state and dilatancy, and the band arithmetic on two results files
    written here."""
    import h5py
    import numpy as np
    os.makedirs(a.dir, exist_ok=True)
    dc = load_script()
    for case, want in (("biaxial_small.opts", (0.5, 0.5)), ("biaxial_5k.opts", (0.5, 0.0))):
        path = os.path.join(ROOT, "cases", case)
        got = dc.case_friction(dc.case_options(path), path)
        check(got == want, f"{case}: friction between disks and against the walls {got}, expected {want}")
        x, rad = np.array([[0.1, 0.1], [0.3, 0.1]]), np.array([0.1, 0.1])
        ns = types.SimpleNamespace(mu=got[0], mu_wall=got[1], lammps_damping=0.0)
        text = dc.lammps_biaxial_input(ns, x, rad, (0.0, 0.0, 0.4, 0.2), 1e3, 1.0, 1e-5, 10, 10, 1, 0.01,
                                       os.path.join(a.dir, "friction"), 1.0)
        ns.lammps_damping = 5.0
        damped = dc.lammps_biaxial_input(ns, x, rad, (0.0, 0.0, 0.4, 0.2), 1e3, 1.0, 1e-5, 10, 10, 1, 0.01,
                                         os.path.join(a.dir, "damped"), 1.0).splitlines()
        drag = [l for l in damped if l.startswith("fix drag disks viscous")]
        shear = damped.index("reset_timestep 0")
        check("fix drag" not in text and len(drag) == 1 and abs(float(drag[0].split()[-1]) - 5.0 * math.pi * 0.01) < 1e-12
              and damped.index("unfix wdamp") < damped.index(drag[0]) < shear, f"{case}: --lammps-damping 5 drags the disks (mean mass pi 0.01 kg/m) "
              f"from the shear on, and 0 does not: {drag}")
        pair = [l for l in text.splitlines() if l.startswith("pair_style")]
        walls = [l for l in text.splitlines() if "wall/gran/region" in l]
        check(len(pair) == 1 and float(pair[0].split()[-2]) == got[0] and len(walls) == 4
              and all(float(l.split()[-5]) == got[1] for l in walls),
              f"{case}: LAMMPS's pair friction {got[0]} and wall friction {got[1]} ({pair}, {walls[:1]})")
    small = os.path.join(ROOT, "cases", "biaxial_small.opts")
    lines = open(small).readlines()
    segment = case_refusal(dc, a.dir, "segment_platens.opts", [l for l in lines if not l.startswith("-wall_box_bottom_infinite")])
    check("the bottom wall is a segment" in segment, f"a case whose bottom platen is a segment is refused: {segment or 'accepted'}")
    unguided = case_refusal(dc, a.dir, "unguided_walls.opts", lines + ["-wall_box_right_guided false\n"])
    check("the right wall is not guided" in unguided, f"a case whose lateral wall slides along itself is refused: {unguided or 'accepted'}")
    dc.check_case(dc.case_options(small), small)  # the case as shipped: guided by default under its pressure
    grid = types.SimpleNamespace(strain=0.10, strain_step=0.0025)
    e = np.array(dc.strain_grid(grid))
    # q/p up to 0.5 at 2 %, down to 0.3 at 5 %, 0.28 from 5 to 6 % and 0.3 beyond: the peak is the largest mean of two
    # neighbouring 0.25 % points, the critical state the mean beyond 6 % (the last 40 %), not beyond 5 %
    q = np.where(e <= 0.02, 0.5 * e / 0.02, np.where(e > 0.06, 0.3, np.where(e >= 0.05, 0.28, 0.5 - 0.2 * (e - 0.02) / 0.03)))
    # eps_v falls with slope -0.5 over one 0.5 % window (2 to 2.5 %), -0.1 elsewhere: sin psi = 0.5 / 2.5 there, and a
    # wider window would dilute it
    ev = -0.1 * e - 0.4 * np.clip(e - 0.02, 0, 0.005)
    late = lambda v_late, v_mid, v_early: list(np.where(e > 0.06, v_late, np.where(e >= 0.05, v_mid, v_early)))
    curves = {"q_over_p": list(q), "strain_volumetric": list(ev), "solid_fraction": late(0.8, 0.79, 0.78), "Z": late(3.0, 2.5, 2.0)}
    m = dc.macroscopic(curves, grid)
    want = {"peak_q": 0.5 - 0.1 * 0.0025 / 0.03, "critical_q": 0.3, "dilatancy": math.degrees(math.asin(0.2)), "solid_fraction": 0.8,
            "Z": 3.0}
    check(all(abs(m[k] - want[k]) < 1e-9 for k in want), f"macroscopic results of known curves {m}, expected {want}")
    files = []
    for i, shift in enumerate((0.0, 0.02)):
        path = os.path.join(a.dir, f"band{i}.h5")
        with h5py.File(path, "w") as f:
            st = f.create_group("stats")
            n = 400
            eps = np.linspace(0.1 / n, 0.1, n)
            st["strain_axial"] = eps
            st["wall_sxx"] = np.ones(n)
            st["wall_syy"] = (1 + 0.4 + shift) / (1 - 0.4 - shift) * np.ones(n)  # q/p 0.4 + shift
            for k, v in (("strain_volumetric", -0.1 * eps), ("solid_fraction", 0.8 + shift + 0 * eps), ("Z", 3 + 0 * eps),
                         ("q_over_p", 0 * eps)):
                st[k] = v
        files.append(path)
    grid.band, grid.band_curves = files, [dc.kergs_curves(grid, path)[1] for path in files]
    run = {"code": "kergs", "setting": "test", "seconds_per_percent": 1.0, **curves}
    s = dc.band_summary(grid, [run])
    b, r = s["band"], s["runs"][0]
    check(abs(b["critical_q"]["mean"] - 0.41) < 1e-9 and abs(b["critical_q"]["band"] - 0.02) < 1e-9,
          f"band of the critical q/p: mean 0.41, band 0.02 ({b['critical_q']})")
    check(abs(r["errors_in_bands"]["critical_q"] - 5.5) < 1e-9 and "critical_q" not in r["within"] and "Z" in r["within"],
          f"a critical q/p of 0.3 lies 5.5 bands from 0.41; Z within a zero band ({r['errors_in_bands']}, {r['within']})")
    # a kergs setting that blew up half way (its curves NaN beyond) is reported, not compared: the next kergs run that
    # reached the strain is the reference, and the LAMMPS level is measured against that one
    half = {k: [v if ei <= 0.05 else float("nan") for v, ei in zip(c, e)] for k, c in curves.items()}
    stopped = {"code": "kergs", "setting": "stopped", "seconds_per_percent": 0.1, "failed": "blow-up (exit 2)", **half}
    lammps = {"code": "lammps", "setting": "level", "seconds_per_percent": 2.0, **curves}
    ns = types.SimpleNamespace(sample="s.h5", x=[0] * 10, ranks=2, case=os.path.join(ROOT, "cases", "biaxial_small.opts"), mu=0.5,
                               mu_wall=0.5, strain=0.10)
    summ = dc.biaxial_summary(ns, [stopped, run, lammps])["summary"]
    check(summ["reference"] == "kergs test" and list(summ["failed"]) == ["kergs stopped"] and list(summ["errors_vs_reference"]) == ["lammps level"]
          and summ["by_level"][0]["kergs"] == "test" and [x["run"] for x in dc.band_summary(grid, [stopped, run])["runs"]] == ["kergs test"],
          f"a run that stopped early is listed as failed and compared with nothing: reference {summ['reference']}, failed "
          f"{list(summ['failed'])}, errors {list(summ['errors_vs_reference'])}")


def check_biaxial(a):
    check_biaxial_reading(a)
    kergs, lmp = run_and_read(a, "biaxial", "dem_compare_biaxial.jsonl", "biaxial.png", "curves", BIAXIAL_FIELDS[:6], None, ())
    for r in kergs + lmp:
        curves = [r.get(k, []) for k in BIAXIAL_FIELDS[6:]]
        check(all(len(c) == 6 and all(math.isfinite(v) for v in c) for c in curves),
              f"{r['code']}: six finite points on every curve")
        sxx = r.get("sxx", [])[1:]
        mean = sum(sxx) / max(len(sxx), 1)
        check(abs(mean - SIGMA3) < SXX_TOL * SIGMA3, f"{r['code']}: lateral wall stress {mean:.4f} is sigma3 {SIGMA3:g} to {SXX_TOL:g}")
        phi = r.get("solid_fraction", [0])
        check(0.80 < min(phi) and max(phi) < 0.83, f"{r['code']}: solid fraction of compact_small's sample ({min(phi):.4f}-{max(phi):.4f})")
    if kergs and lmp:
        k, l = kergs[0], lmp[0]
        check(k["strain_axial"] == l["strain_axial"], "the curves are at the same axial strains")
        check(0.5 < l["overlap_mean_sigma3"] / l["overlap_target"] < 2,
              f"LAMMPS mean overlap at sigma3 {l['overlap_mean_sigma3']:.2e} near its target {l['overlap_target']:.0e}")
        diff = [abs(p - q) for e, p, q in zip(k["strain_axial"], k["q_over_p"], l["q_over_p"]) if e >= QP_FROM - 1e-12]
        check(bool(diff) and max(diff) < QP_TOL,
              f"LAMMPS's q/p agrees with kergs's within {QP_TOL:g} from {100 * QP_FROM:g} % axial strain (worst {max(diff or [0]):.3f})")
    print("check_dem_compare --scene biaxial: " + ("all checks hold" if not failures else f"{len(failures)} failed"))
    return 1 if failures else 0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--kergs", required=True)
    ap.add_argument("--dir", required=True)
    ap.add_argument("--scene", choices=("lattice", "pressure", "biaxial"), default="lattice")
    a = ap.parse_args()
    if a.scene == "biaxial":
        return check_biaxial(a)
    if a.scene == "pressure":
        return check_pressure(a)
    kergs, lmp = run_and_read(a, None, "dem_compare.jsonl", "forces.png", "force history", FIELDS, "forces",
                              ("time", "top_y", "right_x"))
    for r in kergs + lmp:
        check(0.8 < r["packing"] < 0.92, f"{r['code']}: packing fraction of a dense hex lattice ({r['packing']:.4f})")
        fy = [f["top_y"] for f in r["forces"]]
        check(len(fy) == 5 and all(b > a_ for a_, b in zip(fy, fy[1:])) and fy[0] > 0,
              f"{r['code']}: the top wall force grows as the wall advances ({fy})")
    if kergs and lmp:
        k, l = kergs[0], lmp[0]
        check([round(f["time"], 9) for f in k["forces"]] == [round(f["time"], 9) for f in l["forces"]],
              "the force histories are at the same times")
        ratios = [max(abs(x[c]), abs(y[c])) / max(min(abs(x[c]), abs(y[c])), 1e-300)
                  for x, y in list(zip(k["forces"], l["forces"]))[1:] for c in ("top_y", "right_x")]
        check(max(ratios) < 10, f"kergs and LAMMPS wall forces agree within a factor 10 (worst {max(ratios):.2f})")
        check(0.5 < l["overlap_max"] / l["overlap_target"] < 2,
              f"LAMMPS overlap {l['overlap_max']:.2e} near its target {l['overlap_target']:.0e}")
        check(0 < k["overlap_max"] < 0.05, f"kergs interpenetration bounded ({k['overlap_max']:.2e} of d)")
    print("check_dem_compare: " + ("all checks hold" if not failures else f"{len(failures)} failed"))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
