#!/usr/bin/python3
"""The XDMF file kergs writes beside its results (-output_xdmf, docs/results.md "XDMF file for ParaView"), opened headless
with the XDMF reader of ParaView's VTK (vtkXdmfReader, Debian's python3-paraview) and compared with the HDF5 file read
with h5py, at every time step it lists.

  check_xdmf.py --kergs build/kergs --mpiexec mpiexec --dir WORKDIR

  done      confine500, 6 steps on 2 ranks, a snapshot every 2: the time steps are the snapshots' times; per step the
            disks (points, vertex cells, radius), the contacts (one 2-node line per contact, its ends the centres of
            its disks or a disk's centre and its contact point on the wall, rn and rt the columns of r), the walls (their
            endpoints); the file references the results under their final name
  killed    SIGKILL during a run: the XDMF file references the .tmp, lists only snapshots the .tmp holds whole, and opens
  restart   3 + 3 steps continued from a checkpoint: the same time series as the 6-step run
  off       -output_xdmf false writes none
Exit status 0 when every check holds, 1 otherwise."""
import argparse
import os
import shutil
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline
from vtkmodules.vtkIOXdmf2 import vtkXdmfReader

from checks import check, failures

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
CONFINE500 = os.path.join(ROOT, "cases", "confine500.opts")
VTK_POLY_VERTEX, VTK_POLY_LINE = 2, 4  # the reader's cells for Xdmf's Polyvertex and Polyline


def read_xdmf(path):
    """Every time step of the file: (time, [disks, contacts, walls] as vtkUnstructuredGrid)."""
    r = vtkXdmfReader()
    r.SetFileName(path)
    r.UpdateInformation()
    times = r.GetOutputInformation(0).Get(vtkStreamingDemandDrivenPipeline.TIME_STEPS()) or ()
    steps = []
    for t in times:
        r.UpdateTimeStep(t)
        out = r.GetOutputDataObject(0)
        blocks = []
        for b in range(out.GetNumberOfBlocks()):
            g = out.GetBlock(b)
            copy = g.NewInstance()
            copy.DeepCopy(g)
            blocks.append((out.GetMetaData(b).Get(out.NAME()), copy))
        steps.append((t, blocks))
    return steps


def points(g):
    return vtk_to_numpy(g.GetPoints().GetData())[:, :2]


def cell_array(g, name):
    a = g.GetCellData().GetArray(name)
    return vtk_to_numpy(a) if a is not None else None


def compare_step(h5, k, t, blocks, label):
    """The XDMF's time step against /snapshots/<k> of the HDF5 file."""
    s = h5["snapshots"][f"{k:06d}"]
    n, m, w = int(s.attrs["ndisks"]), int(s.attrs["ncontacts"]), int(s.attrs["nwalls"])
    x, radius, r = s["x"][()], s["radius"][()], s["r"][()].reshape(-1, 2)
    ok = t == float(s.attrs["time"]) and [b[0] for b in blocks] == ["disks", "contacts", "walls"]
    if not check(ok, f"{label}: time step {k} is snapshot {k} (time {t}), blocks disks, contacts, walls"):
        return
    disks, contacts, walls = (b[1] for b in blocks)
    pr = vtk_to_numpy(disks.GetPointData().GetArray("radius"))
    check(disks.GetNumberOfPoints() == n and disks.GetNumberOfCells() == n and disks.GetCellType(0) == VTK_POLY_VERTEX
          and disks.GetCell(n - 1).GetNumberOfPoints() == 1
          and np.array_equal(points(disks), x) and np.array_equal(pr, radius),
          f"{label}, step {s.attrs['step']}: {disks.GetNumberOfPoints()} disk points and one-point cells, positions and radii "
          f"equal to the HDF5's {n}")
    check(contacts.GetNumberOfCells() == m and (m == 0 or contacts.GetNumberOfPoints() == 2 * m)
          and all(contacts.GetCellType(c) == VTK_POLY_LINE and contacts.GetCell(c).GetNumberOfPoints() == 2 for c in range(m)),
          f"{label}, step {s.attrs['step']}: {contacts.GetNumberOfCells()} contact lines, the HDF5's {m}")
    if m > 0:
        rn, rt = cell_array(contacts, "rn"), cell_array(contacts, "rt")
        check(rn is not None and np.array_equal(rn, r[:, 0]) and np.array_equal(rt, r[:, 1]) and np.any(rn > 0),
              f"{label}, step {s.attrs['step']}: normal and tangential impulses (rn, rt) equal the columns of r "
              f"(largest rn {np.max(rn) if rn is not None else float('nan'):.3g})")
        p = points(contacts).reshape(m, 4)
        a, b, kind, nrm = (s["a"][()].astype(int), s["b"][()].astype(int), s["kind"][()].astype(int), s["n"][()])
        ends = np.where((kind == 0)[:, None], x[np.where(kind == 0, b, 0)], x[a] - radius[a, None] * nrm)
        check(np.array_equal(p[:, :2], x[a]) and np.allclose(p[:, 2:], ends, rtol=0, atol=1e-15) and 0 < np.sum(kind) < m,
              f"{label}, step {s.attrs['step']}: each line joins the centre of disk a to the centre of disk b, or to its "
              f"contact point on the wall ({np.sum(kind)} disk-wall contacts)")
    check(walls.GetNumberOfCells() == w and np.array_equal(points(walls).reshape(w, 4), s["walls"][()]),
          f"{label}, step {s.attrs['step']}: {w} wall lines with the HDF5's endpoints")


def check_series(xdmf, h5path, label, final=True):
    text = open(xdmf).read()
    h5name = os.path.basename(h5path) + ("" if final else ".tmp")
    check(f">{h5name}:/snapshots/" in text and (final == (".h5.tmp:" not in text)),
          f"{label}: {os.path.basename(xdmf)} references {h5name}")
    steps = read_xdmf(xdmf)
    with h5py.File(h5path if final else h5path + ".tmp", "r") as h5:
        nsnap = int(h5.attrs["nsnapshots"])
        check(0 < len(steps) <= nsnap, f"{label}: {len(steps)} time steps, of the {nsnap} snapshots in the file")
        for k, (t, blocks) in enumerate(steps):
            compare_step(h5, k, t, blocks, label)
    return steps


def kergs(a, ranks, *args):
    return [a.mpiexec, "-n", str(ranks), a.kergs] + [str(x) for x in args]


def run(a, ranks, *args):
    p = subprocess.run(kergs(a, ranks, *args), cwd=ROOT, capture_output=True, text=True)
    if p.returncode:
        print(p.stdout + p.stderr)
    return p.returncode


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--kergs", required=True)
    ap.add_argument("--mpiexec", default="mpiexec")
    ap.add_argument("--dir", required=True)
    a = ap.parse_args()
    a.kergs = os.path.abspath(a.kergs)
    shutil.rmtree(a.dir, ignore_errors=True)
    os.makedirs(a.dir)
    d = os.path.abspath(a.dir)
    base = ["-options_file", CONFINE500, "-quiet", "-output_every", 2]

    # done: the whole series, opened from another directory than the run's (the references are relative to the XDMF)
    out = os.path.join(d, "done", "c.h5")
    check(run(a, 2, *base, "-steps", 6, "-output", out) == 0, "done: kergs ran 6 steps on 2 ranks")
    os.chdir("/")
    steps = check_series(os.path.join(d, "done", "c.xdmf"), out, "done")
    check(len(steps) == 4 and not os.path.exists(os.path.join(d, "done", "c.xdmf.tmp")),
          f"done: {len(steps)} time steps (steps 0, 2, 4, 6), no c.xdmf.tmp left")

    # restart: 3 + 3 steps give the same series
    out2 = os.path.join(d, "restart", "c.h5")
    ckpt = os.path.join(d, "restart", "c.checkpoint.h5")
    check(run(a, 2, *base, "-steps", 3, "-output", out2, "-checkpoint_every", 3) == 0
          and run(a, 2, "-restart", ckpt, "-steps", 6) == 0, "restart: 3 steps, then 3 more from the checkpoint")
    steps2 = check_series(os.path.join(d, "restart", "c.xdmf"), out2, "restart")
    check([s[0] for s in steps2] == [s[0] for s in steps], "restart: the continued run's time steps are the 6-step run's")

    # killed: the XDMF of a run killed midway references the .tmp and opens
    out3 = os.path.join(d, "killed", "c.h5")
    log = os.path.join(d, "killed.log")
    with open(log, "w") as f:
        p = subprocess.Popen(kergs(a, 2, "-options_file", CONFINE500, "-steps", 100000, "-output", out3, "-output_every", 5,
                                   "-output_flush_seconds", 0), cwd=ROOT, stdout=f, stderr=subprocess.STDOUT)
    t0 = time.time()
    while time.time() - t0 < 60 and p.poll() is None and sum(1 for line in open(log) if line.startswith("step ")) < 30:
        time.sleep(0.05)
    children = subprocess.run(["ps", "-o", "pid=", "--ppid", str(p.pid)], capture_output=True, text=True).stdout.split()
    for pid in children:
        os.kill(int(pid), signal.SIGKILL)
    p.wait(timeout=60)
    steps3 = check_series(os.path.join(d, "killed", "c.xdmf"), out3, "killed", final=False)
    check(len(steps3) >= 3, f"killed: {len(steps3)} time steps viewable after the kill")

    # off
    out4 = os.path.join(d, "off", "c.h5")
    check(run(a, 1, *base, "-steps", 1, "-output", out4, "-output_xdmf", "false") == 0 and os.path.exists(out4)
          and not os.path.exists(os.path.join(d, "off", "c.xdmf")), "off: -output_xdmf false writes no XDMF file")
    print(f"xdmf: {len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
