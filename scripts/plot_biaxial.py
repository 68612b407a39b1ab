#!/usr/bin/python3
"""Draw a biaxial test's macroscopic response from a kergs results file's /stats (docs/results.md, "Macroscopic
response"): two PNGs against the axial strain.

Usage: scripts/plot_biaxial.py RESULTS.h5 [-o PREFIX]

  PREFIX_stress.png     q/p and the volumetric strain (positive in compression, so dilatancy goes down)
  PREFIX_structure.png  the coordination number Z (all grains and without rattlers) and the solid fraction

PREFIX defaults to RESULTS without .h5. The file must come from a run whose four walls form a box (box_area > 0 in
some row): without a box the strains and the stress are not defined, and the script says so.
The shebang is /usr/bin/python3 on purpose: Debian's h5py and matplotlib import only there.
"""
import argparse
import sys

import h5py
import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

NEEDED = ["box_area", "strain_axial", "strain_volumetric", "q_over_p", "Z", "Z_nonrattler", "solid_fraction"]


def fail(message):
    sys.exit(f"plot_biaxial.py: {message}")


def read_stats(path):
    """The columns the plots need, over the rows where the walls formed a box."""
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        fail(f"cannot open {path} as HDF5: {e}")
    with f:
        missing = [k for k in NEEDED if "stats" not in f or k not in f["stats"]]
        if missing:
            fail(f"{path}: /stats has no {', '.join(missing)} (a results file of an older kergs?)")
        cols = {k: f["stats"][k][()] for k in NEEDED}
    rows = cols["box_area"] > 0
    if not rows.any():
        fail(f"{path}: the walls never form a box (box_area is 0 in every row): no strain to plot against")
    return {k: v[rows] for k, v in cols.items()}


def two_axes(x, left, right, xlabel, out):
    """One figure: the curves of `left` on the left axis, of `right` on the right one; each a list of (y, label, style)."""
    fig, ax = plt.subplots(figsize=(6, 4), dpi=120)
    twin = ax.twinx()
    for axis, curves, colour in [(ax, left, "tab:blue"), (twin, right, "tab:red")]:
        for y, label, style in curves:
            axis.plot(100 * x, y, style, color=colour, label=label)
        axis.set_ylabel(", ".join(c[1] for c in curves), color=colour)
    ax.set_xlabel(xlabel)
    lines = ax.get_lines() + twin.get_lines()
    ax.legend(lines, [l.get_label() for l in lines], loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)
    print(f"plot_biaxial.py: wrote {out}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results", help="kergs results file (HDF5)")
    ap.add_argument("-o", "--prefix", help="output prefix (default: RESULTS without .h5)")
    a = ap.parse_args()
    prefix = a.prefix or (a.results[:-3] if a.results.endswith(".h5") else a.results)
    s = read_stats(a.results)
    xlabel = "axial strain (%)"
    two_axes(s["strain_axial"], [(s["q_over_p"], "q/p", "-")], [(100 * s["strain_volumetric"], "volumetric strain (%)", "-")],
             xlabel, prefix + "_stress.png")
    two_axes(s["strain_axial"], [(s["Z"], "Z", "-"), (s["Z_nonrattler"], "Z without rattlers", "--")],
             [(s["solid_fraction"], "solid fraction", "-")], xlabel, prefix + "_structure.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
