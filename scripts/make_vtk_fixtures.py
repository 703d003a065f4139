#!/usr/bin/env python3
"""Writes tests/data/vtk/: one small triangle mesh saved by VTK's own writers in every variant
shellsim reads (legacy 4.2 and 5.1, ASCII and binary; XML ascii, base64, zlib-compressed, UInt64
headers, big-endian; UnstructuredGrid and PolyData; XML with appended data, raw or base64, with
every compressor VTK has (none, zlib, LZ4, LZMA), in both byte orders and header types). The reader tests compare every file with the mesh defined here (see
tests/unit/io.rs). Needs `pip install vtk`; the files are committed, so the tests do not.

    python3 scripts/make_vtk_fixtures.py
"""
import os
import vtk

OUT = os.path.join(os.path.dirname(__file__), "..", "tests", "data", "vtk")


def mesh():
    pts = vtk.vtkPoints()
    pts.SetDataTypeToDouble()
    n = 3
    for j in range(n):
        for i in range(n):
            x, y = i / (n - 1), j / (n - 1)
            pts.InsertNextPoint(x, y, 0.1 * x * y)
    tris = vtk.vtkCellArray()
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i
            for t in ((a, a + 1, a + n + 1), (a, a + n + 1, a + n)):
                tris.InsertNextCell(3, t)
    return pts, tris


def arrays(npts, ncells):
    abar = vtk.vtkDoubleArray()
    abar.SetName("abar_info")
    abar.SetNumberOfComponents(3)
    for f in range(ncells):
        abar.InsertNextTuple3(1.0 + f, 0.125 * f, 2.0 + f)
    vel = vtk.vtkDoubleArray()
    vel.SetName("velocity")
    vel.SetNumberOfComponents(3)
    for v in range(npts):
        vel.InsertNextTuple3(v, -v, 0.5 * v)
    tag = vtk.vtkIntArray()
    tag.SetName("node_tags")
    for v in range(npts):
        tag.InsertNextValue(7 * v - 20)
    return abar, vel, tag


def grid():
    pts, tris = mesh()
    g = vtk.vtkUnstructuredGrid()
    g.SetPoints(pts)
    g.SetCells(vtk.VTK_TRIANGLE, tris)
    abar, vel, tag = arrays(pts.GetNumberOfPoints(), tris.GetNumberOfCells())
    g.GetCellData().AddArray(abar)
    g.GetPointData().AddArray(vel)
    g.GetPointData().AddArray(tag)
    return g


def poly():
    pts, tris = mesh()
    p = vtk.vtkPolyData()
    p.SetPoints(pts)
    p.SetPolys(tris)
    abar, vel, tag = arrays(pts.GetNumberOfPoints(), tris.GetNumberOfCells())
    p.GetCellData().AddArray(abar)
    p.GetPointData().AddArray(vel)
    p.GetPointData().AddArray(tag)
    return p


def xml(writer, data, name, mode, compress=True, header64=False, big=False, compressor="zlib",
        encode=False):
    w = writer()
    w.SetInputData(data)
    w.SetFileName(os.path.join(OUT, name))
    {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary,
     "appended": w.SetDataModeToAppended}[mode]()
    if not compress:
        w.SetCompressorTypeToNone()
    else:
        {"zlib": w.SetCompressorTypeToZLib, "lz4": w.SetCompressorTypeToLZ4,
         "lzma": w.SetCompressorTypeToLZMA}[compressor]()
    if header64:
        w.SetHeaderTypeToUInt64()
    else:
        w.SetHeaderTypeToUInt32()
    w.SetEncodeAppendedData(1 if encode else 0)
    if big:
        w.SetByteOrderToBigEndian()
    assert w.Write() == 1, name


def legacy(writer, data, name, binary, version):
    w = writer()
    w.SetInputData(data)
    w.SetFileName(os.path.join(OUT, name))
    if binary:
        w.SetFileTypeToBinary()
    else:
        w.SetFileTypeToASCII()
    if version == 42:
        w.SetFileVersion(42)
    assert w.Write() == 1, name


def main():
    os.makedirs(OUT, exist_ok=True)
    g, p = grid(), poly()
    U, P = vtk.vtkXMLUnstructuredGridWriter, vtk.vtkXMLPolyDataWriter
    xml(U, g, "ascii.vtu", "ascii")
    xml(U, g, "base64.vtu", "binary", compress=False)
    xml(U, g, "zlib.vtu", "binary")
    xml(U, g, "zlib_uint64.vtu", "binary", header64=True)
    xml(U, g, "base64_bigendian.vtu", "binary", compress=False, big=True)
    xml(P, p, "zlib.vtp", "binary")
    xml(P, p, "ascii.vtp", "ascii")
    # ParaView's default: raw appended data, zlib, UInt64 headers.
    xml(U, g, "appended.vtu", "appended", header64=True)
    xml(U, g, "appended_none.vtu", "appended", compress=False)
    xml(U, g, "appended_lz4.vtu", "appended", compressor="lz4")
    xml(U, g, "appended_lzma.vtu", "appended", compressor="lzma", header64=True)
    xml(U, g, "appended_bigendian.vtu", "appended", big=True, header64=True)
    xml(U, g, "appended_bigendian_none.vtu", "appended", compress=False, big=True)
    xml(U, g, "appended_base64.vtu", "appended", encode=True)
    xml(U, g, "appended_base64_none.vtu", "appended", compress=False, encode=True)
    xml(P, p, "appended.vtp", "appended", header64=True)
    xml(P, p, "appended_bigendian_lz4.vtp", "appended", big=True, compressor="lz4")
    LU, LP = vtk.vtkUnstructuredGridWriter, vtk.vtkPolyDataWriter
    legacy(LU, g, "ascii_51.vtk", False, 51)
    legacy(LU, g, "binary_51.vtk", True, 51)
    legacy(LU, g, "ascii_42.vtk", False, 42)
    legacy(LU, g, "binary_42.vtk", True, 42)
    legacy(LP, p, "poly_ascii_51.vtk", False, 51)
    legacy(LP, p, "poly_binary_42.vtk", True, 42)
    print("VTK", vtk.vtkVersion.GetVTKVersion(), "->", os.path.abspath(OUT))


main()
