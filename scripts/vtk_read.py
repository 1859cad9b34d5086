#!/usr/bin/env python3
"""Reads a VTK XML file (.vtu, .vtp, a parallel .pvtu with its pieces) or a ParaView collection (.pvd) with VTK's own readers
(the library ParaView is built on) and prints what it found as JSON: point and cell counts,
cell types, points, and every point and cell array with its values. The tests of demcon's
writers compare this with what they wrote: an independent reader, not our own parser.

Usage: vtk_read.py FILE    (needs VTK's Python package: pip install vtk)
"""
import json
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy


def arrays(data):
    out = {}
    for i in range(data.GetNumberOfArrays()):
        a = data.GetArray(i)
        out[a.GetName()] = {
            "type": a.GetDataTypeAsString(),
            "components": a.GetNumberOfComponents(),
            "values": vtk_to_numpy(a).ravel().tolist(),
        }
    return out


def read_dataset(path):
    readers = {
        ".vtu": vtk.vtkXMLUnstructuredGridReader,
        ".pvtu": vtk.vtkXMLPUnstructuredGridReader,
        ".vtp": vtk.vtkXMLPolyDataReader,
    }
    reader = readers[path.suffix]()
    reader.SetFileName(str(path))
    errors = vtk.vtkStringOutputWindow()
    vtk.vtkOutputWindow.SetInstance(errors)
    reader.Update()
    if reader.GetErrorCode() != 0 or "ERROR" in errors.GetOutput():
        raise SystemExit(f"VTK could not read {path}: {errors.GetOutput()}")
    d = reader.GetOutput()
    n_cells = d.GetNumberOfCells()
    types = sorted({d.GetCellType(i) for i in range(n_cells)})
    out = {
        "points": d.GetNumberOfPoints(),
        "cells": n_cells,
        "cell_types": types,
        "xyz": vtk_to_numpy(d.GetPoints().GetData()).ravel().tolist() if d.GetNumberOfPoints() else [],
        "point_data": arrays(d.GetPointData()),
        "cell_data": arrays(d.GetCellData()),
    }
    if path.suffix == ".vtp":
        conn = []
        for i in range(n_cells):
            ids = d.GetCell(i).GetPointIds()
            conn.append([ids.GetId(k) for k in range(ids.GetNumberOfIds())])
        out["cell_points"] = conn
    elif 42 in types:
        # Each polyhedron's face count, and its volume from the faces VTK returns (divergence
        # theorem; VTK's own cell-size filter tetrahedralises and is off by up to 1e-2 on
        # slivers).
        xyz = vtk_to_numpy(d.GetPoints().GetData())
        out["cell_faces"], out["cell_volumes"] = [], []
        for i in range(n_cells):
            cell = d.GetCell(i)
            volume = 0.0
            for f in range(cell.GetNumberOfFaces()):
                face = cell.GetFace(f)
                x = xyz[[face.GetPointId(k) for k in range(face.GetNumberOfPoints())]]
                for a, b in zip(x[1:-1], x[2:]):
                    volume += float(x[0] @ np.cross(a, b)) / 6.0
            out["cell_faces"].append(cell.GetNumberOfFaces())
            out["cell_volumes"].append(volume)
    return out


def main():
    path = Path(sys.argv[1])
    if path.suffix == ".pvd":
        root = ET.parse(path).getroot()
        if root.get("type") != "Collection":
            raise SystemExit(f"{path}: not a ParaView collection")
        entries = []
        for ds in root.iter("DataSet"):
            f = path.parent / ds.get("file")
            entries.append({"t": float(ds.get("timestep")), "file": ds.get("file"), "data": read_dataset(f)})
        print(json.dumps({"entries": entries}))
    else:
        print(json.dumps(read_dataset(path)))


if __name__ == "__main__":
    main()
