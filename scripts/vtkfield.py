"""Reads fields of shellsim's legacy ASCII VTK frames (`output.format = "vtk_ascii"`) with the
standard library only. Used by the scene scripts in this folder."""

import sys


def read(path):
    """Returns (points, cells, point_fields, cell_fields) of a legacy ASCII VTK file; each field
    is a list of tuples (one per point or cell)."""
    tokens = open(path).read().split()
    i = 0
    points, cells = [], []
    pfields, cfields = {}, {}
    current = None
    n_points = n_cells = 0

    def take(k):
        nonlocal i
        out = tokens[i:i + k]
        i += k
        return out

    while i < len(tokens):
        t = tokens[i]
        if t == "POINTS":
            n_points = int(tokens[i + 1])
            i += 3
            v = list(map(float, take(3 * n_points)))
            points = [tuple(v[3 * k:3 * k + 3]) for k in range(n_points)]
        elif t == "CELLS" and tokens[i + 1] != "":
            n_cells = int(tokens[i + 1])
            i += 3
            # VTK 4.2 layout: n id0 id1 ... per cell.
            for _ in range(n_cells):
                n = int(take(1)[0])
                cells.append(tuple(map(int, take(n))))
        elif t == "CELL_TYPES":
            i += 2 + int(tokens[i + 1])
        elif t == "POINT_DATA":
            current, i = (pfields, n_points), i + 2
        elif t == "CELL_DATA":
            current, i = (cfields, n_cells), i + 2
        elif t in ("SCALARS", "VECTORS"):
            name = tokens[i + 1]
            if t == "SCALARS":
                ncomp = 1
                i += 3
                if tokens[i] not in ("LOOKUP_TABLE",):
                    ncomp = int(tokens[i])
                    i += 1
                i += 2  # LOOKUP_TABLE default
            else:
                ncomp, i = 3, i + 3
            store, count = current
            v = list(map(float, take(ncomp * count)))
            store[name] = [tuple(v[ncomp * k:ncomp * k + ncomp]) for k in range(count)]
        elif t == "FIELD":
            nf = int(tokens[i + 2])
            i += 3
            store, _ = current
            for _ in range(nf):
                name, ncomp, count = tokens[i], int(tokens[i + 1]), int(tokens[i + 2])
                i += 4
                v = list(map(float, take(ncomp * count)))
                store[name] = [tuple(v[ncomp * k:ncomp * k + ncomp]) for k in range(count)]
        else:
            i += 1
    return points, cells, pfields, cfields


if __name__ == "__main__":
    p, c, pf, cf = read(sys.argv[1])
    print(len(p), "points", len(c), "cells")
    print("point fields:", sorted(pf))
    print("cell fields:", sorted(cf))
