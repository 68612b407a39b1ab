#!/usr/bin/python3
"""A large sample from a small one: the sample mirrored into nx x ny tiles, at rest under the same pressure.

  scripts/tile_sample.py IN.h5 OUT.h5 --tiles NX,NY

IN is a kergs sample compacted in the four walls of -box (it records them in /sample/box). Tile (i, j) is IN
reflected in x when i is odd and in y when j is odd, and shifted by i box widths and j box heights. Every grain that
touched a wall of IN then touches its own mirror image across the seam, along the same normal and, by symmetry, with
the same force: a frictionless compaction's sample at rest under p stays at rest under p, seams included, and OUT is
ready for a test without a second compaction (docs/biaxial.md, "10^6 disks"). Velocities and spins are reflected
with the grains. OUT records the box of the whole tiling, so a test reads it with -box_from_sample.

What it is not: a random sample of NX x NY times IN's size. Its grain-scale disorder repeats with a period of two
tiles, and the seams are mirror lines. Written atomically; IN is never written.
"""
import argparse
import os
import sys

import h5py
import numpy as np


def fail(message):
    sys.exit("tile_sample.py: " + message)


def parse_tiles(text):
    try:
        nx, ny = (int(w) for w in text.split(","))
    except ValueError:
        fail(f"--tiles {text!r}: expected two positive integers NX,NY")
    if nx < 1 or ny < 1 or nx * ny < 2:
        fail(f"--tiles {text!r}: expected NX,NY >= 1 with at least two tiles")
    return nx, ny


def read_sample(path):
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        fail(f"{path}: not a readable HDF5 file ({e})")
    with f:
        if f.attrs.get("kergs_format") not in (b"kergs sample 1", "kergs sample 1") or "sample" not in f:
            fail(f"{path}: not a kergs sample (root attribute kergs_format is not 'kergs sample 1')")
        g = f["sample"]
        if "box" not in g:
            fail(f"{path}: no /sample/box: tiling needs the box the sample was compacted in (-box)")
        data = {k: g[k][()] for k in g if k != "box"}
        attrs = dict(g.attrs)
        box = np.asarray(g["box"][()], dtype=float).reshape(4)
        root = dict(f.attrs)
    if not np.all(np.isfinite(box)) or box[2] <= box[0] or box[3] <= box[1]:
        fail(f"{path}: /sample/box {box.tolist()} is not a box (x0, y0, x1, y1 with x1 > x0, y1 > y0)")
    x = data.get("x")
    if x is None or x.ndim != 2 or x.shape[1] != 2:
        fail(f"{path}: /sample/x is missing or not N x 2 (tiling is 2D)")
    for k, v in data.items():
        if len(v) != len(x):
            fail(f"{path}: /sample/{k} has {len(v)} rows, /sample/x {len(x)}")
        if v.dtype.kind == "f" and not np.all(np.isfinite(v)):
            fail(f"{path}: /sample/{k} holds NaN or infinite values")
    r = data["radius"]
    slack = 0.01 * r.min()  # a compaction leaves grains interpenetrating its walls by its solver's tolerance (1e-7 m)
    if np.any(x - r[:, None] < box[:2] - slack) or np.any(x + r[:, None] > box[2:] + slack):
        fail(f"{path}: grains cross /sample/box by more than 1 % of the smallest radius: the box is not where the walls stood")
    return data, attrs, root, box


def tile(data, box, nx, ny):
    """The mirrored tiling: arrays of nx * ny copies, tile by tile (i fastest)."""
    n = len(data["radius"])
    width, height = box[2] - box[0], box[3] - box[1]
    out = {k: [] for k in data}
    for j in range(ny):
        for i in range(nx):
            t = j * nx + i
            flip = np.array([-1.0 if i % 2 else 1.0, -1.0 if j % 2 else 1.0])
            u = data["x"] - box[:2]
            u = np.where(flip > 0, u, np.array([width, height]) - u)
            handed = flip[0] * flip[1]  # a reflection reverses the sense of rotation, two restore it
            for k, v in data.items():
                if k == "x":
                    v = box[:2] + np.array([i * width, j * height]) + u
                elif k == "v":
                    v = v * flip
                elif k in ("omega", "rot"):
                    v = v * handed
                elif k == "id":
                    v = v + n * t
                out[k].append(np.asarray(v, dtype=data[k].dtype))
    return {k: np.concatenate(v) for k, v in out.items()}, np.array([box[0], box[1], box[0] + nx * width, box[1] + ny * height])


def write_sample(path, root, attrs, data, box):
    tmp = path + ".tmp"
    with h5py.File(tmp, "w") as h:
        for k, v in root.items():
            h.attrs[k] = v
        g = h.create_group("sample")
        for k, v in attrs.items():
            g.attrs[k] = v
        g.attrs["ndisks"] = np.asarray(len(data["radius"]), dtype=np.asarray(attrs["ndisks"]).dtype)
        for k, v in data.items():
            g.create_dataset(k, data=v)
        g.create_dataset("box", data=box.reshape(1, 4))
    os.replace(tmp, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("input")
    ap.add_argument("output")
    ap.add_argument("--tiles", required=True, help="NX,NY")
    a = ap.parse_args()
    nx, ny = parse_tiles(a.tiles)
    if not os.path.isfile(a.input):
        fail(f"{a.input}: no such file")
    if os.path.exists(a.output) and not os.path.isfile(a.output):
        fail(f"{a.output}: exists and is not a regular file")
    if os.path.exists(a.output) and os.path.samefile(a.input, a.output):
        fail(f"{a.output}: is the input; write the tiling elsewhere")
    data, attrs, root, box = read_sample(a.input)
    tiled, tiled_box = tile(data, box, nx, ny)
    write_sample(a.output, root, attrs, tiled, tiled_box)
    print(f"tile_sample.py: {a.output}: {len(tiled['radius'])} disks ({nx} x {ny} mirrored tiles of {len(data['radius'])}), box "
          + ",".join(f"{b:.9g}" for b in tiled_box))


if __name__ == "__main__":
    main()
