#!/usr/bin/python3
"""ctest io_plot: draw a results file with scripts/plot_packing.py and check the picture it writes.

Usage: tests/check_plot.py results.h5 out.png

Passes when plot_packing.py exits 0 and out.png (removed first, so that an old picture cannot pass) is a valid PNG
(signature, IHDR chunk first with a sensible size, IEND last, CRCs right), of non-trivial size, that decodes
(matplotlib) to a picture that is not blank: more than 2% of its pixels differ from the background colour, in at
least 3 distinct colours (disks, walls and text, force chains). Prints one line per check, as the C tests do.
The shebang is /usr/bin/python3 on purpose: Debian's matplotlib imports only there.
"""
import os
import struct
import subprocess
import sys
import zlib

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
PLOT = os.path.join(HERE, "..", "scripts", "plot_packing.py")
nfail = 0


def check(ok, what, got, want):
    global nfail
    print(f"{'ok  ' if ok else 'FAIL'} {what:<72} got {got} want {want}")
    if not ok:
        nfail += 1
    return ok


def png_chunks(data):
    """The chunks of a PNG as (type, payload, crc_ok), or None if the signature is wrong."""
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        return None
    chunks, pos = [], 8
    while pos + 12 <= len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind, payload = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        (crc,) = struct.unpack(">I", data[pos + 8 + length:pos + 12 + length] or b"\0\0\0\0")
        chunks.append((kind, payload, zlib.crc32(kind + payload) & 0xFFFFFFFF == crc))
        pos += 12 + length
    return chunks


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    results, png = sys.argv[1], sys.argv[2]
    if os.path.exists(png):
        os.remove(png)
    run = subprocess.run([sys.executable, PLOT, results, "-o", png], capture_output=True, text=True)
    sys.stdout.write(run.stdout + run.stderr)
    check(run.returncode == 0, "plot_packing.py exits 0", run.returncode, 0)
    if not check(os.path.isfile(png), "the PNG exists", os.path.isfile(png), True):
        return
    data = open(png, "rb").read()
    check(len(data) > 5000, "the PNG is of non-trivial size (bytes)", len(data), "> 5000")
    chunks = png_chunks(data)
    if not check(chunks is not None, "PNG signature", chunks is not None, True):
        return
    kinds = [c[0] for c in chunks]
    check(bool(kinds) and kinds[0] == b"IHDR" and kinds[-1] == b"IEND" and b"IDAT" in kinds,
          "chunks: IHDR first, IDAT, IEND last", [k.decode("latin-1") for k in kinds[:3]] + ["..."], "IHDR ... IEND")
    check(all(c[2] for c in chunks), "every chunk's CRC is right", sum(not c[2] for c in chunks), 0)
    if kinds and kinds[0] == b"IHDR":
        width, height = struct.unpack(">II", chunks[0][1][:8])
        check(width >= 200 and height >= 100, "IHDR: width x height", f"{width}x{height}", ">= 200x100")
    try:
        img = mpimg.imread(png)
    except Exception as e:  # a corrupt stream
        check(False, "the PNG decodes", repr(e), "an image")
        return
    rgb = np.round(255 * np.asarray(img)[..., :3]).astype(np.int64).reshape(-1, 3)
    codes = (rgb[:, 0] << 16) | (rgb[:, 1] << 8) | rgb[:, 2]
    values, counts = np.unique(codes, return_counts=True)
    background = values[np.argmax(counts)]
    drawn = float(np.mean(codes != background))
    check(drawn > 0.02, "not blank: fraction of pixels off the background", f"{drawn:.4f}", "> 0.02")
    # colours that cover at least 0.1% of the picture each (anti-aliasing blends do not count)
    major = int(np.sum(counts >= 0.001 * codes.size)) - 1
    check(major >= 3, "distinct colours besides the background (>= 0.1% each)", major, ">= 3")


if __name__ == "__main__":
    main()
    print(f"{'FAILED' if nfail else 'PASSED'}: {nfail} failed checks")
    sys.exit(1 if nfail else 0)
