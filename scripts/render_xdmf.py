#!/usr/bin/python3
"""Render one time step of a kergs XDMF file (written beside the results, docs/results.md "XDMF file for ParaView")
headless with VTK, as ParaView shows it: disks drawn to scale from their radius, force chains as tubes whose radius
and colour grow with the normal impulse rn, walls as lines.

  scripts/render_xdmf.py results/confine500.xdmf -o docs/confine500_xdmf.png [--step K] [--width 640]

It reads the file with the XDMF reader ParaView uses (vtkXdmfReader, from Debian's python3-paraview) and renders
off screen; without a display it runs itself again under xvfb-run (Debian's xvfb)."""
import argparse
import os
import shutil
import sys

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline
from vtkmodules.vtkFiltersCore import vtkCellDataToPointData, vtkGlyph3D, vtkTubeFilter
from vtkmodules.vtkFiltersGeometry import vtkGeometryFilter
from vtkmodules.vtkFiltersSources import vtkRegularPolygonSource
from vtkmodules.vtkIOImage import vtkPNGWriter
from vtkmodules.vtkIOXdmf2 import vtkXdmfReader
from vtkmodules.vtkRenderingCore import (vtkActor, vtkColorTransferFunction, vtkPolyDataMapper, vtkRenderer,
                                         vtkRenderWindow, vtkWindowToImageFilter)
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (the OpenGL back end)


def blocks_at(path, step):
    """The disks, contacts and walls grids of time step `step` (negative: from the end), and its time."""
    r = vtkXdmfReader()
    r.SetFileName(path)
    r.UpdateInformation()
    times = r.GetOutputInformation(0).Get(vtkStreamingDemandDrivenPipeline.TIME_STEPS())
    t = times[step]
    r.UpdateTimeStep(t)
    out = r.GetOutputDataObject(0)
    grids = {}
    for b in range(out.GetNumberOfBlocks()):
        g = out.GetBlock(b)
        copy = g.NewInstance()
        copy.DeepCopy(g)
        grids[out.GetMetaData(b).Get(out.NAME())] = copy
    return grids, t, len(times)


def polydata(grid):
    f = vtkGeometryFilter()
    f.SetInputData(grid)
    f.Update()
    return f.GetOutput()


def disks_actors(disks):
    """A filled circle of the disk's radius at every point, and its outline (what ParaView's Point Gaussian
    representation draws with the radius array as scale)."""
    pd = polydata(disks)
    pd.GetPointData().SetActiveScalars("radius")
    actors = []
    for fill in (True, False):
        circle = vtkRegularPolygonSource()
        circle.SetNumberOfSides(32)
        circle.SetRadius(1.0)
        circle.SetGeneratePolygon(fill)
        g = vtkGlyph3D()
        g.SetInputData(pd)
        g.SetSourceConnection(circle.GetOutputPort())
        g.SetScaleModeToScaleByScalar()
        g.SetScaleFactor(1.0)
        m = vtkPolyDataMapper()
        m.SetInputConnection(g.GetOutputPort())
        m.ScalarVisibilityOff()
        a = vtkActor()
        a.SetMapper(m)
        a.GetProperty().SetColor(*((0.9, 0.9, 0.88) if fill else (0.6, 0.6, 0.6)))
        a.GetProperty().SetLighting(False)
        a.SetPosition(0, 0, 0 if fill else 1e-4)  # the outline over the fill (the camera looks down -z)
        actors.append(a)
    return actors


def chains_actor(contacts, rmean):
    """Tubes along the contact lines: radius and colour proportional to rn, the widest 0.3 mean disk radius."""
    if contacts.GetNumberOfCells() == 0:
        return None
    c2p = vtkCellDataToPointData()  # each line has its own 2 points: they get the line's rn exactly
    c2p.SetInputData(polydata(contacts))
    c2p.Update()
    pd = c2p.GetOutput()
    rn = vtk_to_numpy(pd.GetPointData().GetArray("rn"))
    rmax = float(rn.max())
    width = numpy_to_vtk(np.maximum(rn, 0.0) * (0.3 * rmean / max(rmax, 1e-300)), deep=1)  # tube radius, in m
    width.SetName("tube_radius")
    pd.GetPointData().AddArray(width)
    pd.GetPointData().SetActiveScalars("tube_radius")
    tube = vtkTubeFilter()
    tube.SetInputData(pd)
    tube.SetVaryRadiusToVaryRadiusByAbsoluteScalar()
    tube.SetNumberOfSides(6)
    colors = vtkColorTransferFunction()
    colors.AddRGBPoint(0.0, 0.85, 0.45, 0.35)
    colors.AddRGBPoint(rmax, 0.45, 0.0, 0.0)
    m = vtkPolyDataMapper()
    m.SetInputConnection(tube.GetOutputPort())
    m.SetScalarModeToUsePointFieldData()
    m.SelectColorArray("rn")
    m.SetLookupTable(colors)
    m.SetScalarRange(0.0, rmax)
    a = vtkActor()
    a.SetMapper(m)
    a.GetProperty().SetLighting(False)
    a.SetPosition(0, 0, 2 * rmean)  # over the disks: the tubes are rmean thick at most
    return a


def walls_actor(walls):
    m = vtkPolyDataMapper()
    m.SetInputData(polydata(walls))
    m.ScalarVisibilityOff()
    a = vtkActor()
    a.SetMapper(m)
    a.GetProperty().SetColor(0.1, 0.1, 0.1)
    a.GetProperty().SetLineWidth(3)
    return a


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("xdmf")
    ap.add_argument("-o", "--output", required=True, help="PNG file")
    ap.add_argument("--step", type=int, default=-1, help="time step of the file (default: the last)")
    ap.add_argument("--width", type=int, default=640, help="picture width in pixels")
    a = ap.parse_args()
    if not os.environ.get("DISPLAY"):
        if not shutil.which("xvfb-run"):
            sys.exit("render_xdmf.py: no DISPLAY and no xvfb-run (Debian package xvfb)")
        os.execvp("xvfb-run", ["xvfb-run", "-a", "-s", "-screen 0 1600x1600x24", sys.executable] + sys.argv)
    grids, t, ntimes = blocks_at(a.xdmf, a.step)
    disks = grids["disks"]
    radius = vtk_to_numpy(disks.GetPointData().GetArray("radius"))
    ren = vtkRenderer()
    ren.SetBackground(1, 1, 1)
    for actor in disks_actors(disks):
        ren.AddActor(actor)
    chains = chains_actor(grids["contacts"], float(np.mean(radius)))
    if chains:
        ren.AddActor(chains)
    ren.AddActor(walls_actor(grids["walls"]))
    x = vtk_to_numpy(disks.GetPoints().GetData())
    lo, hi = x.min(axis=0) - radius.max(), x.max(axis=0) + radius.max()
    height = int(round(a.width * (hi[1] - lo[1]) / (hi[0] - lo[0])))
    cam = ren.GetActiveCamera()
    cam.ParallelProjectionOn()
    centre = (lo + hi) / 2
    cam.SetFocalPoint(centre[0], centre[1], 0)
    cam.SetPosition(centre[0], centre[1], 10)
    cam.SetViewUp(0, 1, 0)
    cam.SetParallelScale(0.51 * (hi[1] - lo[1]))
    win = vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.AddRenderer(ren)
    win.SetSize(a.width, height)
    win.Render()
    grab = vtkWindowToImageFilter()
    grab.SetInput(win)
    grab.Update()
    png = vtkPNGWriter()
    png.SetFileName(a.output)
    png.SetCompressionLevel(9)
    png.SetInputConnection(grab.GetOutputPort())
    png.Write()
    print(f"render_xdmf.py: time step {a.step % ntimes} of {ntimes} (t = {t:.6g} s): {disks.GetNumberOfPoints()} disks, "
          f"{grids['contacts'].GetNumberOfCells()} contacts -> {a.output}")


if __name__ == "__main__":
    main()
