#!/usr/bin/python3
"""The macroscopic response in /stats (src/step/macro.c, docs/results.md "Macroscopic response"), through the executable:

1. recomputed here from the last snapshot's contacts and disks (an independent implementation, numpy), on 1 and 2
   ranks: every figure of the step's row agrees to 1e-9 relative (the stresses, the boundary's included, Z with and without rattlers, the
   anisotropies, the sliding fraction, the solid fraction, the strains);
2. statics: cases/confine500's deposit at rest in its closed box (walls at rest, gravity, friction 0.3: kinetic
   energy about 4e-11 J/m) - the Love-Weber sxx equals the boundary's exactly (the moment of every wall traction,
   friction included, over the box area) to 1e-6 relative, and the wall stress wall_sxx (normal forces over the
   wall's length) to 3 %: the measured gap is 2.0 %, the floor's friction, which wall_sxx leaves out;
3. a frictionless run (-friction 0) has no sliding contact and a_t = 0, while the case's own run (its right wall
   pushing) has sliding contacts, and strains equal to the wall's travel over the box;
4. a run with an open box records the box-dependent figures as 0, never NaN.

  check_macro.py --kergs build/kergs --mpiexec mpiexec --dir WORKDIR
Exit status 0 when every check holds, 1 otherwise."""
import sys

import h5py
import numpy as np

from checks import Kergs, check, failures

CONFINE = ["-options_file", "cases/confine500.opts", "-box_open_top", "0", "-wall_box_right_velocity", "0,0", "-quiet"]
STATIC_TOL = 1e-6  # Love-Weber against the boundary's moment (measured 1e-9 with newton to 1e-8)
WALL_TOL = 0.03  # Love-Weber sxx against wall_sxx on the frictional floor (measured 2.0 %)


def principal(xx, yy, xy):
    mean, rad = 0.5 * (xx + yy), np.hypot(0.5 * (xx - yy), xy)
    return mean + rad, mean - rad


def rattlers(ngrains, a, b, dd):
    """Grains with fewer than 2 contacts, removed round after round; returns the mask and the counts left."""
    rat = np.zeros(ngrains, bool)
    while True:
        keep = ~rat[a] & (~dd | ~rat[np.where(dd, b, 0)])
        counts = np.bincount(a[keep], minlength=ngrains) + np.bincount(b[keep & dd], minlength=ngrains)
        new = ~rat & (counts < 2)
        if not new.any():
            return rat, counts
        rat |= new


def recompute(snap, dt, mu):
    """The row's figures from the snapshot alone (a 4-wall box, walls in the order bottom, right, top, left)."""
    x, rad = snap["x"][()], snap["radius"][()]
    a, b, kind = snap["a"][()].astype(int), snap["b"][()].astype(int), snap["kind"][()].astype(int)
    n, r, walls = snap["n"][()], snap["r"][()], snap["walls"][()]
    t = np.stack([-n[:, 1], n[:, 0]], axis=1)
    on = r[:, 0] > 0
    a, b, kind, n, t, r = a[on], b[on], kind[on], n[on], t[on], r[on]
    dd = kind == 0
    f = (r[:, :1] * n + r[:, 1:2] * t) / dt
    l = np.where(dd[:, None], x[a] - x[np.where(dd, b, 0)], rad[a][:, None] * n)
    x0, x1, y0, y1 = walls[3, 0], walls[1, 0], walls[0, 1], walls[2, 1]
    area = (x1 - x0) * (y1 - y0)
    s = np.einsum("ci,cj->ij", f, l) / area
    out = {"sxx": s[0, 0], "syy": s[1, 1], "sxy": 0.5 * (s[0, 1] + s[1, 0]), "box_area": area}
    out["s1"], out["s2"] = principal(out["sxx"], out["syy"], out["sxy"])
    out["q_over_p"] = (out["s1"] - out["s2"]) / (out["s1"] + out["s2"])
    wallforce = np.bincount(b[~dd], weights=r[~dd, 0] / dt, minlength=4)
    out["wall_sxx"] = 0.5 * (wallforce[1] + wallforce[3]) / (y1 - y0)
    out["wall_syy"] = 0.5 * (wallforce[0] + wallforce[2]) / (x1 - x0)
    out["solid_fraction"] = np.pi * np.sum(rad**2) / area
    ng = len(rad)
    out["Z"] = (2 * dd.sum() + (~dd).sum()) / ng
    rat, counts = rattlers(ng, a, b, dd)
    out["rattler_fraction"] = rat.sum() / ng
    out["Z_nonrattler"] = counts[~rat].sum() / (~rat).sum()
    out["sliding_fraction"] = np.sum((mu > 0) & (np.abs(r[:, 1]) >= mu * r[:, 0] * (1 - 1e-6))) / len(r)
    nd, td, fn, ft = n[dd], t[dd], r[dd, 0], r[dd, 1]
    F = np.einsum("ci,cj->ij", nd, nd)
    chin = np.einsum("c,ci,cj->ij", fn, nd, nd) / fn.sum()
    chit = np.einsum("c,ci,cj->ij", ft, td, nd) / fn.sum()
    chit = 0.5 * (chit + chit.T)
    f1, f2 = principal(F[0, 0], F[1, 1], F[0, 1])
    n1, n2 = principal(chin[0, 0], chin[1, 1], chin[0, 1])
    t1, t2 = principal(*(chin + chit)[[0, 1, 0], [0, 1, 1]])
    out["a_c"] = 2 * (f1 - f2) / (f1 + f2)
    out["a_n"] = 2 * (n1 - n2) / (n1 + n2) - out["a_c"]
    out["a_t"] = 2 * (t1 - t2) / (n1 + n2) - out["a_c"] - out["a_n"]
    # the boundary's side of the Love identity (statics, gravity along y): the moment of every wall traction about the
    # box's centre
    cpoint = x[a[~dd]] - rad[a[~dd]][:, None] * n[~dd] - np.array([0.5 * (x0 + x1), 0.5 * (y0 + y1)])
    b = -np.einsum("ci,cj->ij", f[~dd], cpoint) / area
    out["boundary_sxx"], out["boundary_syy"], out["boundary_sxy"] = b[0, 0], b[1, 1], 0.5 * (b[0, 1] + b[1, 0])
    return out


def last_row(path):
    with h5py.File(path, "r") as h:
        st = h["stats"]
        row = {k: st[k][-1] for k in st}
        snap = h["snapshots"][sorted(h["snapshots"])[-1]]
        check(int(snap.attrs["step"]) == int(row["step"]), f"{path}: the last snapshot is the last row's step")
        return row, {k: snap[k][()] for k in snap}


def agree(tag, row, ref, names):
    for k in names:
        ok = np.isfinite(row[k]) and abs(row[k] - ref[k]) <= 1e-9 * max(1.0, abs(ref[k]))
        check(ok, f"{tag}: {k} = {row[k]:.12g}, recomputed {ref[k]:.12g}")


def static_confined(k, ranks):
    out = k.path(f"static_{ranks}.h5")
    p = k.run(ranks, *CONFINE, "-steps", 3, "-output", out, "-output_every", 1)
    if not check(p.returncode == 0, f"static on {ranks} rank(s): kergs exits 0 {p.stderr[-300:]}"):
        return
    row, snap = last_row(out)
    ref = recompute(snap, 2e-4, 0.3)
    agree(f"static, {ranks} rank(s)", row, ref, list(ref))
    rel = abs(row["sxx"] / ref["boundary_sxx"] - 1)
    check(rel < STATIC_TOL, f"static, {ranks} rank(s): Love-Weber sxx {row['sxx']:.6g} = boundary {ref['boundary_sxx']:.6g} "
          f"(relative {rel:.1e} < {STATIC_TOL})")
    rel = abs(row["sxx"] / row["wall_sxx"] - 1)
    check(rel < WALL_TOL, f"static, {ranks} rank(s): sxx {row['sxx']:.6g} against wall_sxx {row['wall_sxx']:.6g} "
          f"(relative {rel:.3f} < {WALL_TOL})")
    check(row["kinetic_energy"] < 1e-9, f"static: at rest (kinetic energy {row['kinetic_energy']:.2e})")


def frictionless(k):
    out = k.path("frictionless.h5")
    p = k.run(1, *CONFINE, "-friction", 0, "-steps", 3, "-output", out, "-output_every", 1)
    if not check(p.returncode == 0, f"frictionless: kergs exits 0 {p.stderr[-300:]}"):
        return
    row, snap = last_row(out)
    check(row["sliding_fraction"] == 0, f"frictionless: sliding_fraction {row['sliding_fraction']} = 0")
    check(abs(row["a_t"]) < 1e-12, f"frictionless: a_t {row['a_t']:.2e} = 0")
    check(row["Z"] > 0 and row["q_over_p"] > 0, "frictionless: a loaded network (Z > 0, q/p > 0)")
    agree("frictionless", row, recompute(snap, 2e-4, 0.0), ["Z", "Z_nonrattler", "rattler_fraction", "a_c", "a_n"])


def pushed(k):
    """confine500 as its case runs it (the right wall pushing at 0.05 m/s) in a closed box: sliding contacts, strains."""
    out = k.path("pushed.h5")
    args = [a for a in CONFINE if a not in ("-wall_box_right_velocity", "0,0")]
    p = k.run(1, *args, "-steps", 5, "-output", out, "-output_every", 1)
    if not check(p.returncode == 0, f"pushed: kergs exits 0 {p.stderr[-300:]}"):
        return
    row, snap = last_row(out)
    ref = recompute(snap, 2e-4, 0.3)
    check(row["sliding_fraction"] > 0.1, f"pushed: contacts slide (sliding_fraction {row['sliding_fraction']:.3f})")
    agree("pushed", row, ref, ["sliding_fraction", "sxx", "wall_sxx", "boundary_sxx", "boundary_syy", "boundary_sxy", "Z_nonrattler", "a_t"])
    lateral = 5 * 2e-4 * 0.05 / 0.5  # 5 steps of the right wall over the 0.5 m wide box
    for name, want in [("strain_lateral", lateral), ("strain_axial", 0.0), ("strain_volumetric", lateral)]:
        check(abs(row[name] - want) < 1e-12, f"pushed: {name} {row[name]:.6g} = {want:.6g}")


def open_box(k):
    out = k.path("open.h5")
    p = k.run(1, "-options_file", "cases/confine500.opts", "-quiet", "-steps", 2, "-output", out)
    if not check(p.returncode == 0, f"open box: kergs exits 0 {p.stderr[-300:]}"):
        return
    with h5py.File(out, "r") as h:
        st = h["stats"]
        for name in ["box_area", "sxx", "q_over_p", "wall_sxx", "solid_fraction", "strain_axial"]:
            check(np.all(st[name][()] == 0), f"open box: {name} is 0 in every row")
        check(np.all(st["Z"][()] > 0), "open box: Z is still recorded")


def main():
    k = Kergs.from_command_line(__doc__.splitlines()[0])
    for ranks in (1, 2):
        static_confined(k, ranks)
    frictionless(k)
    pushed(k)
    open_box(k)
    print(f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
