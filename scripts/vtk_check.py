#!/usr/bin/env python3
"""Reads shellsim's frames with VTK's own readers and checks them against what shellsim says they
hold: the point and cell counts, the field names and component counts, positions and a few values
of every field, and each run's series.pvd (parsed with VTK's XML parser), whose entries must name
the frames in time order.

    python3 scripts/vtk_check.py EXPECT.json

EXPECT.json (written by tests/vtk_python.rs):
    {"frames": [{"file", "points", "cells", "positions": [[i, x, y, z], ...],
                 "point_fields" / "cell_fields": {name: {"components", "samples": [[i, v...]],
                                                         "tol"}}}],
     "series": [{"pvd", "files": [...], "times": [...]}]}

Needs VTK's Python package (`scripts/test.sh` installs it into `.venv/`). Exits 1 listing every
mismatch, 0 when all hold.
"""
import json
import os
import sys

try:
    import vtk
except ImportError:
    sys.exit("VTK's Python package is missing: scripts/test.sh installs it into .venv/")

errors = []


def fail(where, what):
    errors.append(f"{where}: {what}")


def close(a, b, tol):
    return abs(a - b) <= tol * max(1.0, abs(b))


def read(path):
    if path.endswith(".vtu"):
        r = vtk.vtkXMLUnstructuredGridReader()
    else:
        r = vtk.vtkUnstructuredGridReader()
        r.ReadAllScalarsOn()
        r.ReadAllVectorsOn()
        r.ReadAllFieldsOn()
    r.SetFileName(path)
    r.Update()
    return r.GetOutput()


def check_fields(where, data, expected):
    names = sorted(data.GetArrayName(i) for i in range(data.GetNumberOfArrays()))
    if names != sorted(expected):
        fail(where, f"fields {names}, expected {sorted(expected)}")
    for name, e in expected.items():
        arr = data.GetArray(name)
        if arr is None:
            continue
        if arr.GetNumberOfComponents() != e["components"]:
            fail(where, f"'{name}' has {arr.GetNumberOfComponents()} components, expected "
                        f"{e['components']}")
            continue
        for s in e["samples"]:
            i, want = s[0], s[1:]
            got = [arr.GetComponent(i, c) for c in range(e["components"])]
            if not all(close(g, w, e["tol"]) for g, w in zip(got, want)):
                fail(where, f"'{name}'[{i}] = {got}, expected {want}")


def check_frame(f):
    where = f["file"]
    if not os.path.exists(where):
        fail(where, "missing")
        return
    g = read(where)
    if g is None or g.GetNumberOfPoints() != f["points"]:
        fail(where, f"{g.GetNumberOfPoints() if g else 0} points, expected {f['points']}")
        return
    if g.GetNumberOfCells() != f["cells"]:
        fail(where, f"{g.GetNumberOfCells()} cells, expected {f['cells']}")
    for c in range(g.GetNumberOfCells()):
        if g.GetCellType(c) != vtk.VTK_TRIANGLE:
            fail(where, f"cell {c} has VTK type {g.GetCellType(c)}, expected a triangle")
            break
    for i, x, y, z in f["positions"]:
        p = g.GetPoint(i)
        if p != (x, y, z):
            fail(where, f"point {i} = {p}, expected {(x, y, z)} exactly")
    check_fields(where + " PointData", g.GetPointData(), f["point_fields"])
    check_fields(where + " CellData", g.GetCellData(), f["cell_fields"])


def check_series(s):
    where = s["pvd"]
    p = vtk.vtkXMLDataParser()
    p.SetFileName(where)
    if not p.Parse():
        fail(where, "VTK's XML parser rejects it")
        return
    root = p.GetRootElement()
    if root.GetName() != "VTKFile" or root.GetAttribute("type") != "Collection":
        fail(where, f"root <{root.GetName()} type={root.GetAttribute('type')}>")
        return
    coll = root.FindNestedElementWithName("Collection")
    files, times = [], []
    for k in range(coll.GetNumberOfNestedElements()):
        d = coll.GetNestedElement(k)
        files.append(d.GetAttribute("file"))
        times.append(float(d.GetAttribute("timestep")))
    if files != s["files"]:
        fail(where, f"lists {files}, expected {s['files']}")
    if any(not close(a, b, 1e-12) for a, b in zip(times, s["times"])):
        fail(where, f"times {times}, expected {s['times']}")
    base = os.path.dirname(where)
    for name in files:
        if not os.path.exists(os.path.join(base, name)):
            fail(where, f"lists '{name}', which does not exist")


def main():
    spec = json.load(open(sys.argv[1]))
    for f in spec["frames"]:
        check_frame(f)
    for s in spec["series"]:
        check_series(s)
    if errors:
        print("\n".join(errors))
        sys.exit(1)
    print(f"VTK {vtk.vtkVersion.GetVTKVersion()}: {len(spec['frames'])} frames and "
          f"{len(spec['series'])} series read as expected")


main()
