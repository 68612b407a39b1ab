#!/usr/bin/python3
"""Draw one snapshot of a kergs results file: disks, walls and force chains.

Usage: scripts/plot_packing.py results.h5 [-o out.png] [--snapshot K]

Force chains are drawn as in the figures of Alart (2013): a segment between the centres of the two disks
of each contact (from the disk centre to the contact point for a disk-wall contact), its width
proportional to the normal impulse r_n, the largest about 0.6 times the mean disk radius; contacts with
no compressive impulse are not drawn. The layout of the file is in docs/results.md.

The shebang is /usr/bin/python3 on purpose: Debian's h5py and matplotlib import only there.
"""
import argparse
import os
import sys

import h5py
import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import LineCollection, PatchCollection  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402

CHAIN_MAX_WIDTH = 0.6  # widest force chain, in mean disk radii


def fail(message):
    sys.exit(f"plot_packing.py: {message}")


def read_snapshot(path, which):
    """Return a dict with the datasets and attributes of snapshot `which` (None: the last)."""
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        fail(f"cannot open {path} as HDF5: {e}")
    with f:
        if "snapshots" not in f or len(f["snapshots"]) == 0:
            fail(f"{path} has no /snapshots (was the run started with -output_none?)")
        names = sorted(f["snapshots"].keys())
        if which is None:
            name = names[-1]
        else:
            name = f"{which:06d}"
            if name not in f["snapshots"]:
                fail(f"{path} has no snapshot {which} (it has {len(names)}: 0..{len(names) - 1})")
        g = f["snapshots"][name]
        snap = {key: np.asarray(g[key][()]) for key in g.keys()}
        snap["step"] = int(np.asarray(g.attrs["step"]).ravel()[0])
        snap["time"] = float(np.asarray(g.attrs["time"]).ravel()[0])
        snap["name"] = name
    for key in ("x", "radius"):
        if key not in snap:
            fail(f"{path}: snapshot {name} lacks dataset {key}")
    snap["x"] = snap["x"].reshape(-1, 2)
    if snap["radius"].shape[0] != snap["x"].shape[0]:
        fail(f"{path}: snapshot {name} has {snap['x'].shape[0]} positions but {snap['radius'].shape[0]} radii")
    if "walls" in snap:
        snap["walls"] = snap["walls"].reshape(-1, 4)
    for key in ("n", "r"):
        if key in snap:
            snap[key] = snap[key].reshape(-1, 2)
    return snap


def nearest_on_line(a, b, p):
    """Point of the line through a and b nearest to p."""
    d = (b - a) / max(np.hypot(*(b - a)), 1e-300)
    return a + np.dot(p - a, d) * d


def plot_limits(snap):
    """Bounding box of the disks, of the finite walls and of the point of each infinite wall nearest to
    the disks, with a margin."""
    x, rad = snap["x"], snap["radius"]
    lo = (x - rad[:, None]).min(axis=0) if len(rad) else np.zeros(2)
    hi = (x + rad[:, None]).max(axis=0) if len(rad) else np.ones(2)
    walls = snap.get("walls", np.zeros((0, 4)))
    infinite = snap.get("wall_infinite", np.zeros(len(walls)))
    centre = 0.5 * (lo + hi)
    for w, inf in zip(walls, infinite):
        points = [nearest_on_line(w[:2], w[2:], centre)] if inf else [w[:2], w[2:]]
        for p in points:
            lo, hi = np.minimum(lo, p), np.maximum(hi, p)
    margin = 0.05 * max(hi[0] - lo[0], hi[1] - lo[1], 1e-12)
    return lo - margin, hi + margin


def wall_segments(snap, lo, hi):
    """Wall segments; an infinite wall (a line) is cut to the plotted box."""
    walls = snap.get("walls", np.zeros((0, 4)))
    infinite = snap.get("wall_infinite", np.zeros(len(walls)))
    span = 2.0 * np.hypot(*(hi - lo))
    segments = []
    for w, inf in zip(walls, infinite):
        a, b = w[:2], w[2:]
        if inf:
            d = (b - a) / max(np.hypot(*(b - a)), 1e-300)
            foot = nearest_on_line(a, b, 0.5 * (lo + hi))
            a, b = foot - span * d, foot + span * d  # longer than the box: clipped by the axes
        segments.append([a, b])
    return segments


def chain_segments(snap):
    """Force-chain segments and their normal impulses (only r_n > 0)."""
    if "r" not in snap or len(snap["r"]) == 0:
        return np.zeros((0, 2, 2)), np.zeros(0)
    x, rad = snap["x"], snap["radius"]
    a = snap["a"].astype(int)
    b = snap["b"].astype(int)
    kind = snap["kind"].astype(int)
    rn = snap["r"][:, 0]
    start = x[a]
    end = np.empty_like(start)
    disk = kind == 0
    end[disk] = x[b[disk]]
    # disk-wall: contact point c = x_a - R_a n (n points from the wall towards the disk)
    end[~disk] = x[a[~disk]] - rad[a[~disk], None] * snap["n"][~disk]
    keep = rn > 0
    return np.stack([start[keep], end[keep]], axis=1), rn[keep]


def points_per_unit(ax):
    """Length of one data unit along x, in typographic points (after limits and aspect are fixed)."""
    fig = ax.figure
    p0, p1 = ax.transData.transform([(0.0, 0.0), (1.0, 0.0)])
    return abs(p1[0] - p0[0]) * 72.0 / fig.dpi


def draw(snap, out, title_prefix):
    lo, hi = plot_limits(snap)
    aspect = (hi[1] - lo[1]) / max(hi[0] - lo[0], 1e-12)
    width = 9.0 if aspect <= 1.0 else max(9.0 / aspect, 5.0)  # the longer side about 9 inches
    fig, ax = plt.subplots(figsize=(width, width * aspect + 0.8), dpi=150)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    fig.canvas.draw()  # fixes the data-to-points scale used for the chain widths

    disks = [Circle(c, r) for c, r in zip(snap["x"], snap["radius"])]
    ax.add_collection(PatchCollection(disks, facecolor="0.88", edgecolor="0.45", linewidth=0.3, zorder=1))
    walls = wall_segments(snap, lo, hi)
    if walls:
        ax.add_collection(LineCollection(walls, colors="black", linewidths=2.0, zorder=3))
    segments, rn = chain_segments(snap)
    if len(rn):
        mean_radius = float(np.mean(snap["radius"]))
        max_width = CHAIN_MAX_WIDTH * mean_radius * points_per_unit(ax)
        widths = max_width * rn / rn.max()
        ax.add_collection(LineCollection(segments, colors="firebrick", linewidths=widths, capstyle="round", zorder=2))
    ax.set_title(f"{title_prefix}step {snap['step']}, t = {snap['time']:.6g}\n"
                 f"{len(snap['radius'])} disks, {len(rn)} loaded contacts", fontsize=10)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    tmp = out + ".tmp"
    fig.savefig(tmp, format="png", bbox_inches="tight")
    plt.close(fig)
    os.replace(tmp, out)  # atomic: a reader never sees a half-written PNG


def main():
    parser = argparse.ArgumentParser(description="Draw disks, walls and force chains of a kergs results file.")
    parser.add_argument("results", help="kergs results file (HDF5)")
    parser.add_argument("-o", "--output", help="PNG to write (default: <results>-<snapshot>.png)")
    parser.add_argument("--snapshot", type=int, default=None, help="snapshot index K (default: the last)")
    args = parser.parse_args()
    snap = read_snapshot(args.results, args.snapshot)
    out = args.output or f"{os.path.splitext(args.results)[0]}-{snap['name']}.png"
    draw(snap, out, f"{os.path.basename(args.results)}: ")
    print(f"plot_packing.py: snapshot {snap['name']} (step {snap['step']}) of {args.results} drawn in {out}")


if __name__ == "__main__":
    main()
