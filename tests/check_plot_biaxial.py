#!/usr/bin/python3
"""ctest plot_biaxial: scripts/plot_biaxial.py on a short run whose top wall moves down into confine500's deposit in a
closed box (the axial strain grows): it exits 0 and writes PREFIX_stress.png and PREFIX_structure.png (removed first,
so that old pictures cannot pass), each a PNG that decodes to a picture that is not blank (more than 2 % of its pixels
differ from white, in at least 3 colours: two curves and the text); on an open box's results it refuses, naming the
reason (no box, so no strain).

  check_plot_biaxial.py --kergs build/kergs --mpiexec mpiexec --dir WORKDIR
The shebang is /usr/bin/python3 on purpose: Debian's h5py and matplotlib import only there."""
import os
import subprocess
import sys

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402

from checks import ROOT, Kergs, check, failures

PLOT = os.path.join(ROOT, "scripts", "plot_biaxial.py")
BIAXIAL = ["-options_file", "cases/confine500.opts", "-box", "0,0,0.5,0.98", "-box_open_top", "0", "-wall_box_right_velocity",
           "0,0", "-wall_box_top_velocity", "0,-0.05", "-steps", 10, "-quiet"]


def picture(path):
    if not check(os.path.exists(path), f"{path} written"):
        return
    img = mpimg.imread(path)
    pixels = img[:, :, :3].reshape(-1, 3)
    drawn = np.any(np.abs(pixels - 1.0) > 0.02, axis=1)
    colours = len(np.unique(np.round(pixels[drawn] * 8), axis=0))
    check(img.shape[0] > 200 and img.shape[1] > 300, f"{path}: {img.shape[1]}x{img.shape[0]} pixels")
    check(drawn.mean() > 0.02 and colours >= 3, f"{path}: not blank ({100 * drawn.mean():.1f} % drawn, {colours} colours)")


def main():
    k = Kergs.from_command_line(__doc__.splitlines()[0])
    out, prefix = k.path("biaxial.h5"), k.path("biaxial")
    for suffix in ("_stress.png", "_structure.png"):
        if os.path.exists(prefix + suffix):
            os.remove(prefix + suffix)
    p = k.run(1, *BIAXIAL, "-output", out)
    if check(p.returncode == 0, f"kergs exits 0 {p.stderr[-300:]}"):
        p = subprocess.run([sys.executable, PLOT, out, "-o", prefix], capture_output=True, text=True)
        check(p.returncode == 0, f"plot_biaxial.py exits 0 {p.stderr[-300:]}")
        picture(prefix + "_stress.png")
        picture(prefix + "_structure.png")
    open_box = k.path("open.h5")
    p = k.run(1, "-options_file", "cases/confine500.opts", "-steps", 1, "-quiet", "-output", open_box)
    if check(p.returncode == 0, f"open box: kergs exits 0 {p.stderr[-300:]}"):
        p = subprocess.run([sys.executable, PLOT, open_box, "-o", k.path("open")], capture_output=True, text=True)
        check(p.returncode != 0 and "never form a box" in p.stderr, f"open box: refused ({p.stderr.strip()})")
    print(f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
