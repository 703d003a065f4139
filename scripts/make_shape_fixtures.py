#!/usr/bin/env python3
"""Writes the OFF, OBJ, PLY and STL fixtures of tests/data/shapes/ (standard library only).

A unit cube with quad faces (outward, counter-clockwise seen from outside) in OFF, OBJ and PLY
(ASCII, binary little- and big-endian; the PLY faces carry a `ref_thicknesses` property), and
an icosahedron as STL (ASCII and binary). The tests read each and compare with the cube's and
icosahedron's known volume, area and counts; the fuzzer mutates them.
"""
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "tests", "data", "shapes")

CUBE_V = [(x, y, z) for z in (0.0, 1.0) for y in (0.0, 1.0) for x in (0.0, 1.0)]
# Quads counter-clockwise seen from outside.
CUBE_F = [
    (0, 2, 3, 1),  # z = 0
    (4, 5, 7, 6),  # z = 1
    (0, 1, 5, 4),  # y = 0
    (2, 6, 7, 3),  # y = 1
    (0, 4, 6, 2),  # x = 0
    (1, 3, 7, 5),  # x = 1
]


def icosahedron():
    t = (1.0 + math.sqrt(5.0)) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    return v, f


def write(name, data, mode="w"):
    with open(os.path.join(OUT, name), mode) as fh:
        fh.write(data)


def main():
    os.makedirs(OUT, exist_ok=True)
    # OFF with a comment, counts on their own line, colours after the indices.
    off = "OFF\n# a unit cube of quads\n%d %d 12\n" % (len(CUBE_V), len(CUBE_F))
    off += "".join("%g %g %g\n" % p for p in CUBE_V)
    off += "".join("4 %d %d %d %d 255 0 0\n" % f for f in CUBE_F)
    write("cube.off", off)
    # OBJ with texture and normal indices and negative (relative) indices in the last face.
    obj = "# a unit cube of quads\no cube\n" + "".join("v %g %g %g\n" % p for p in CUBE_V)
    obj += "vt 0 0\nvn 0 0 1\n"
    for i, f in enumerate(CUBE_F):
        if i == len(CUBE_F) - 1:
            obj += "f " + " ".join("%d/1/1" % (v - len(CUBE_V)) for v in f) + "\n"
        else:
            obj += "f " + " ".join("%d//1" % (v + 1) for v in f) + "\n"
    write("cube.obj", obj)
    # PLY, ASCII and binary, with a per-face thickness.
    header = ("ply\nformat %s 1.0\ncomment a unit cube of quads\nelement vertex %d\n"
              "property float x\nproperty float y\nproperty float z\nelement face %d\n"
              "property list uchar int vertex_indices\nproperty double ref_thicknesses\n"
              "end_header\n")
    ply = header % ("ascii", len(CUBE_V), len(CUBE_F))
    ply += "".join("%g %g %g\n" % p for p in CUBE_V)
    ply += "".join("4 %d %d %d %d 0.001\n" % f for f in CUBE_F)
    write("cube_ascii.ply", ply)
    for fmt, e, name in (("binary_little_endian", "<", "cube_le.ply"),
                         ("binary_big_endian", ">", "cube_be.ply")):
        b = (header % (fmt, len(CUBE_V), len(CUBE_F))).encode()
        for p in CUBE_V:
            b += struct.pack(e + "3f", *p)
        for f in CUBE_F:
            b += struct.pack(e + "B4id", 4, *f, 0.001)
        write(name, b, "wb")
    # STL, ASCII and binary.
    v, f = icosahedron()
    stl = "solid ico\n"
    for t in f:
        stl += "  facet normal 0 0 0\n    outer loop\n"
        stl += "".join("      vertex %.9g %.9g %.9g\n" % v[i] for i in t)
        stl += "    endloop\n  endfacet\n"
    stl += "endsolid ico\n"
    write("ico_ascii.stl", stl)
    b = b"binary icosahedron".ljust(80, b" ") + struct.pack("<I", len(f))
    for t in f:
        b += struct.pack("<3f", 0, 0, 0)
        for i in t:
            b += struct.pack("<3f", *v[i])
        b += struct.pack("<H", 0)
    write("ico_binary.stl", b, "wb")


if __name__ == "__main__":
    main()
