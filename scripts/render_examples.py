#!/usr/bin/env python3
"""Renders the example pictures of docs/outputs.md from run folders, with VTK (offscreen):

  render_examples.py series   RUN_DIR OUT.png   # particles.pvd: the temperature at each time
  render_examples.py contacts RUN_DIR OUT.png   # contacts.vtp: every contact by its Joule power

The pictures show what ParaView shows for the same files (the same VTK pipeline): a check
by eye that the series and the network are what the run computed. Needs VTK's Python
package (pip install vtk).
"""
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import vtk


def window(width, height):
    w = vtk.vtkRenderWindow()
    w.SetOffScreenRendering(1)
    w.SetSize(width, height)
    return w


def save(w, path):
    w.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(w)
    grab.Update()
    png = vtk.vtkPNGWriter()
    png.SetFileName(str(path))
    png.SetInputConnection(grab.GetOutputPort())
    png.Write()


def text(ren, s, x, y, size=18):
    t = vtk.vtkTextActor()
    t.SetInput(s)
    t.GetTextProperty().SetFontSize(size)
    t.GetTextProperty().SetColor(0, 0, 0)
    t.SetPosition(x, y)
    ren.AddViewProp(t)


def scalar_bar(ren, lut, title, fmt="%.3g"):
    bar = vtk.vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetTitle(title)
    bar.SetNumberOfLabels(5)
    bar.SetLabelFormat(fmt)
    for p in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty()):
        p.SetColor(0, 0, 0)
        p.SetFontSize(14)
        p.ItalicOff()
        p.ShadowOff()
    bar.SetUnconstrainedFontSize(True)
    bar.GetPositionCoordinate().SetValue(0.1, 0.1)
    bar.SetWidth(0.35)
    bar.SetHeight(0.8)
    ren.AddViewProp(bar)


def lookup(lo, hi, log=False):
    lut = vtk.vtkLookupTable()
    if log:
        lut.SetScaleToLog10()
    lut.SetRange(lo, hi)
    lut.SetHueRange(0.667, 0.0)
    lut.Build()
    return lut


def series(run, out):
    """Particles with z below the mid-plane as spheres, coloured by temperature, one panel per
    time of particles.pvd (seen from +z: the cut face)."""
    pvd = Path(run) / "particles.pvd"
    entries = [(float(d.get("timestep")), Path(run) / d.get("file")) for d in ET.parse(pvd).getroot().iter("DataSet")]
    readers = []
    lo, hi = float("inf"), float("-inf")
    for _, f in entries:
        r = vtk.vtkXMLUnstructuredGridReader()
        r.SetFileName(str(f))
        r.Update()
        t0, t1 = r.GetOutput().GetPointData().GetArray("temperature").GetRange()
        lo, hi = min(lo, t0), max(hi, t1)
        readers.append(r)
    lut = lookup(lo, hi)
    panel = 360
    w = window(panel * len(entries) + 110, panel + 40)
    for k, ((t, _), r) in enumerate(zip(entries, readers)):
        d = r.GetOutput()
        zmid = sum(d.GetBounds()[4:6]) / 2
        clip = vtk.vtkExtractGeometry()
        plane = vtk.vtkPlane()
        plane.SetOrigin(0, 0, zmid)
        plane.SetNormal(0, 0, 1)
        clip.SetImplicitFunction(plane)
        clip.SetInputData(d)
        clip.ExtractInsideOn()
        sphere = vtk.vtkSphereSource()
        sphere.SetThetaResolution(10)
        sphere.SetPhiResolution(8)
        sphere.SetRadius(1.0)
        glyph = vtk.vtkGlyph3D()
        glyph.SetInputConnection(clip.GetOutputPort())
        glyph.SetSourceConnection(sphere.GetOutputPort())
        glyph.SetInputArrayToProcess(0, 0, 0, 0, "radius")
        glyph.SetScaleModeToScaleByScalar()
        glyph.SetScaleFactor(1.0)
        glyph.SetColorModeToColorByScalar()
        glyph.Update()
        glyph.GetOutput().GetPointData().SetActiveScalars("temperature")
        m = vtk.vtkPolyDataMapper()
        m.SetInputConnection(glyph.GetOutputPort())
        m.SetScalarModeToUsePointFieldData()
        m.SelectColorArray("temperature")
        m.SetLookupTable(lut)
        m.UseLookupTableScalarRangeOn()
        a = vtk.vtkActor()
        a.SetMapper(m)
        ren = vtk.vtkRenderer()
        ren.SetViewport(k * panel / w.GetSize()[0], 0, (k + 1) * panel / w.GetSize()[0], 1)
        ren.SetBackground(1, 1, 1)
        ren.AddActor(a)
        ren.ResetCamera()
        ren.GetActiveCamera().Zoom(1.1)
        text(ren, f"t = {t:g} s  (cut at mid-depth, y up)", 10, panel + 14, 16)
        w.AddRenderer(ren)
    bar = vtk.vtkRenderer()
    bar.SetViewport(panel * len(entries) / w.GetSize()[0], 0, 1, 1)
    bar.SetBackground(1, 1, 1)
    scalar_bar(bar, lut, "T (°C)")
    w.AddRenderer(bar)
    save(w, out)


def contacts(run, out):
    """Every contact of contacts.vtp (kind 0) as a line coloured by its Joule power, log scale."""
    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(str(Path(run) / "contacts.vtp"))
    r.Update()
    keep = vtk.vtkThreshold()
    keep.SetInputConnection(r.GetOutputPort())
    keep.SetInputArrayToProcess(0, 0, 0, vtk.vtkDataObject.FIELD_ASSOCIATION_CELLS, "kind")
    keep.SetLowerThreshold(-0.5)
    keep.SetUpperThreshold(0.5)
    keep.Update()
    power = keep.GetOutput().GetCellData().GetArray("joule_power")
    lo, hi = power.GetRange()
    lut = lookup(max(lo, hi * 1e-4), hi, log=True)
    m = vtk.vtkDataSetMapper()
    m.SetInputConnection(keep.GetOutputPort())
    m.SetScalarModeToUseCellFieldData()
    m.SelectColorArray("joule_power")
    m.SetLookupTable(lut)
    m.UseLookupTableScalarRangeOn()
    a = vtk.vtkActor()
    a.SetMapper(m)
    a.GetProperty().SetLineWidth(1.5)
    w = window(1000, 480)
    ren = vtk.vtkRenderer()
    ren.SetViewport(0, 0, 0.84, 1)
    ren.SetBackground(1, 1, 1)
    ren.AddActor(a)
    cam = ren.GetActiveCamera()
    cam.SetPosition(1, 0, 0)
    cam.SetFocalPoint(0, 0, 0)
    cam.SetViewUp(0, 0, 1)
    ren.ResetCamera()
    cam.Azimuth(90)
    cam.Roll(90)
    ren.ResetCamera()
    cam.Zoom(1.5)
    text(ren, "every contact coloured by its Joule power (log scale); z to the right", 10, 450, 16)
    w.AddRenderer(ren)
    bar = vtk.vtkRenderer()
    bar.SetViewport(0.84, 0, 1, 1)
    bar.SetBackground(1, 1, 1)
    scalar_bar(bar, lut, "P (W)", "%.1e")
    w.AddRenderer(bar)
    save(w, out)


if __name__ == "__main__":
    kind, run, out = sys.argv[1:4]
    {"series": series, "contacts": contacts}[kind](run, out)
