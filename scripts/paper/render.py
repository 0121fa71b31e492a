#!/usr/bin/env python3
"""Renders key frames of MedSpring runs to PNG with VTK, coloured by displacement (used by `medspring paper`).

usage: render.py JOBS.json

JOBS.json = {"width": W, "height": H, "jobs": [job, ...]} where a job is
  png        output file
  vtp        surface frame written by `medspring run` (point data: displacement_magnitude, Normals, ...)
  array      point array that colours the surface (default displacement_magnitude)
  range      [lo, hi] of the colour map (mm)
  color_label  title of the colour bar
  rest_vtp   optional: the rest surface, drawn as a faint wireframe for comparison
  atoms_vtp  optional: the centerline atoms of the same frame, drawn as a thin tube
  view       direction from the focal point to the camera; up: the camera's up vector
  focus      optional focal point (mm) for a close-up; zoom: > 1 moves the camera closer
  arrow      optional {"point": tip (mm), "direction": force direction, "length": mm}
  title, subtitle  text drawn in the top-left corner

Debian's VTK renders through X only: run this under `xvfb-run -a -s "-screen 0 1280x960x24"`.
"""
import faulthandler
import json
import math
import sys

import vtk
from matplotlib import colormaps


def lookup_table(lo, hi):
    lut = vtk.vtkLookupTable()
    lut.SetNumberOfTableValues(256)
    cmap = colormaps["viridis"]
    for i in range(256):
        r, g, b, _ = cmap(i / 255.0)
        lut.SetTableValue(i, r, g, b, 1.0)
    lut.SetTableRange(lo, hi if hi > lo else lo + 1e-9)
    lut.Build()
    return lut


def read(path):
    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(path)
    r.Update()
    out = r.GetOutput()
    if out is None or out.GetNumberOfPoints() == 0:
        raise RuntimeError(f"{path}: no points")
    return out


def text_actor(text, size, x, y, bold=False):
    t = vtk.vtkTextActor()
    t.SetInput(text)
    p = t.GetTextProperty()
    p.SetFontSize(size)
    p.SetColor(0.05, 0.05, 0.05)
    p.SetBold(bold)
    p.SetFontFamilyToArial()
    t.SetDisplayPosition(x, y)
    return t


def render(job, width, height):
    surf = read(job["vtp"])
    array = job.get("array", "displacement_magnitude")
    pd = surf.GetPointData()
    if pd.GetArray(array) is None:
        raise RuntimeError(f"{job['vtp']}: no point array {array}")
    pd.SetActiveScalars(array)
    if pd.GetArray("Normals") is not None:
        pd.SetNormals(pd.GetArray("Normals"))
    lo, hi = job.get("range", [0.0, pd.GetArray(array).GetRange()[1]])
    lut = lookup_table(lo, hi)

    ren = vtk.vtkRenderer()
    ren.SetBackground(1, 1, 1)
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputData(surf)
    mapper.SetLookupTable(lut)
    mapper.SetScalarRange(lo, hi if hi > lo else lo + 1e-9)
    mapper.SetScalarModeToUsePointData()
    mapper.SelectColorArray(array)
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().SetInterpolationToPhong()
    actor.GetProperty().SetSpecular(0.2)
    actor.GetProperty().SetSpecularPower(20)
    ren.AddActor(actor)

    bounds_src = [surf]
    if job.get("rest_vtp"):
        rest = read(job["rest_vtp"])
        bounds_src.append(rest)
        m = vtk.vtkPolyDataMapper()
        m.SetInputData(rest)
        m.ScalarVisibilityOff()
        a = vtk.vtkActor()
        a.SetMapper(m)
        a.GetProperty().SetRepresentationToWireframe()
        a.GetProperty().SetColor(0.45, 0.45, 0.45)
        a.GetProperty().SetOpacity(0.22)
        a.GetProperty().SetLineWidth(1.0)
        ren.AddActor(a)
    if job.get("atoms_vtp"):
        atoms = read(job["atoms_vtp"])
        tube = vtk.vtkTubeFilter()
        tube.SetInputData(atoms)
        b = atoms.GetBounds()
        diag = math.sqrt((b[1] - b[0]) ** 2 + (b[3] - b[2]) ** 2 + (b[5] - b[4]) ** 2)
        tube.SetRadius(max(diag * 0.004, 0.05))
        tube.SetNumberOfSides(12)
        m = vtk.vtkPolyDataMapper()
        m.SetInputConnection(tube.GetOutputPort())
        m.ScalarVisibilityOff()
        a = vtk.vtkActor()
        a.SetMapper(m)
        a.GetProperty().SetColor(0.75, 0.1, 0.1)
        ren.AddActor(a)

    # Camera: bounding sphere of the surfaces, seen from `view`.
    bb = [1e300, -1e300] * 3
    for s in bounds_src:
        b = s.GetBounds()
        for k in range(3):
            bb[2 * k] = min(bb[2 * k], b[2 * k])
            bb[2 * k + 1] = max(bb[2 * k + 1], b[2 * k + 1])
    center = [(bb[2 * k] + bb[2 * k + 1]) / 2 for k in range(3)]
    radius = 0.5 * math.sqrt(sum((bb[2 * k + 1] - bb[2 * k]) ** 2 for k in range(3)))
    focal = job.get("focus") or center
    view = job.get("view", [0, 0, 1])
    n = math.sqrt(sum(v * v for v in view))
    view = [v / n for v in view]
    zoom = float(job.get("zoom", 1.0))

    if job.get("arrow"):
        ar = job["arrow"]
        d = ar["direction"]
        dn = math.sqrt(sum(v * v for v in d))
        d = [v / dn for v in d]
        length = float(ar.get("length", radius * 0.3))
        tip = ar["point"]
        start = [tip[k] - d[k] * length for k in range(3)]
        src = vtk.vtkArrowSource()
        src.SetTipLength(0.3)
        src.SetTipRadius(0.08)
        src.SetShaftRadius(0.03)
        src.SetTipResolution(24)
        src.SetShaftResolution(24)
        # the arrow source points along +x from 0 to 1: rotate +x onto d, scale by length
        x = [1.0, 0.0, 0.0]
        axis = [x[1] * d[2] - x[2] * d[1], x[2] * d[0] - x[0] * d[2], x[0] * d[1] - x[1] * d[0]]
        s = math.sqrt(sum(v * v for v in axis))
        angle = math.degrees(math.atan2(s, sum(x[k] * d[k] for k in range(3))))
        tr = vtk.vtkTransform()
        tr.Translate(*start)
        if s > 1e-12:
            tr.RotateWXYZ(angle, *axis)
        elif d[0] < 0:
            tr.RotateWXYZ(180, 0, 0, 1)
        tr.Scale(length, length, length)
        tf = vtk.vtkTransformPolyDataFilter()
        tf.SetTransform(tr)
        tf.SetInputConnection(src.GetOutputPort())
        m = vtk.vtkPolyDataMapper()
        m.SetInputConnection(tf.GetOutputPort())
        a = vtk.vtkActor()
        a.SetMapper(m)
        a.GetProperty().SetColor(0.85, 0.1, 0.1)
        ren.AddActor(a)

    cam = ren.GetActiveCamera()
    cam.SetViewAngle(30)
    dist = radius / math.sin(math.radians(15)) / zoom
    cam.SetFocalPoint(*focal)
    cam.SetPosition(*[focal[k] + view[k] * dist for k in range(3)])
    cam.SetViewUp(*job.get("up", [0, 1, 0]))
    cam.OrthogonalizeViewUp()
    ren.ResetCameraClippingRange()

    bar = vtk.vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetTitle(job.get("color_label", "|u| (mm)"))
    bar.SetNumberOfLabels(5)
    bar.SetLabelFormat("%.3g")
    bar.SetOrientationToVertical()
    bar.SetPosition(0.88, 0.12)
    bar.SetWidth(0.08)
    bar.SetHeight(0.7)
    for p in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty()):
        p.SetColor(0.05, 0.05, 0.05)
        p.SetFontFamilyToArial()
        p.ShadowOff()
        p.ItalicOff()
    bar.GetTitleTextProperty().SetFontSize(14)
    bar.GetLabelTextProperty().SetFontSize(12)
    ren.AddActor2D(bar)
    if job.get("title"):
        ren.AddActor2D(text_actor(job["title"], 20, 14, height - 34, bold=True))
    if job.get("subtitle"):
        for i, line in enumerate(job["subtitle"].split("\n")):
            ren.AddActor2D(text_actor(line, 15, 14, height - 60 - 20 * i))

    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetSize(width, height)
    win.SetMultiSamples(4)
    win.AddRenderer(ren)
    win.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(win)
    grab.ReadFrontBufferOff()
    grab.Update()
    w = vtk.vtkPNGWriter()
    w.SetFileName(job["png"])
    w.SetInputConnection(grab.GetOutputPort())
    w.Write()
    win.Finalize()


def main():
    faulthandler.enable()  # SIGABRT / SIGSEGV in VTK or the GL driver: the Python traceback goes to the log
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    with open(sys.argv[1]) as f:
        spec = json.load(f)
    width = int(spec.get("width", 1000))
    height = int(spec.get("height", 750))
    for job in spec["jobs"]:
        print(f"rendering {job['png']}", flush=True)  # an abort inside VTK names its job in the log
        render(job, width, height)
        print(f"rendered {job['png']}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
