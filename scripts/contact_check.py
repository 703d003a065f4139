#!/usr/bin/env python3
"""Independent check of a self-contact run: no two faces intersect and no two mid-surfaces
come closer than a floor, in every frame.

    contact_check.py REFERENCE_MESH OUT_DIR --exclusion R [--floor D] [--json FILE]
    contact_check.py REFERENCE_MESH OUT_DIR --obstacle FILE [--translate X Y Z]
                     [--push COLUMN EX EY EZ] [--floor D] ...

Reads the reference mesh and every frame of OUT_DIR with VTK's own readers, and, brute force
over every pair of faces that share no vertex (numpy, none of shellsim's code):

* intersection: an edge of one face crossing the other face (segment–triangle test, both ways);
* the minimum distance between the two faces: the smallest of the six vertex–face and nine
  edge–edge distances, computed here by projecting and clamping.

Pairs of the same connected piece of the mesh closer than R in the reference mesh (measured
the same way) are excluded, as shellsim excludes them; faces of separate sheets are always
checked. Prints one line per frame and a JSON summary (the smallest distance over all
frames and pairs, its frame and faces, and the number of intersecting pairs); exits 1 when a
pair intersects or comes below --floor.

With --obstacle, the pairs are instead every face of the sheet with every face of that rigid
mesh (moved by --translate), which stands still: the distance is then from the sheet's
mid-surface to the obstacle's surface. A force-controlled obstacle moves: with --push, each
frame's obstacle is moved further by q (EX, EY, EZ), q the frame's value of the column COLUMN
of OUT_DIR/log.csv (its offset, `obstacle{i}_offset`). --last checks the last frame only.
"""

import argparse
import csv
import glob
import json
import os
import sys

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy


def read(path):
    if path.endswith(".obj"):
        # Wavefront OBJ of triangles, read here: `v` and `f` lines (1-based indices, the
        # `i/t/n` forms allowed), vertices in file order as shellsim numbers them.
        pts, faces = [], []
        with open(path) as f:
            for line in f:
                w = line.split()
                if w and w[0] == "v":
                    pts.append([float(c) for c in w[1:4]])
                elif w and w[0] == "f":
                    faces.append([int(c.split("/")[0]) - 1 for c in w[1:4]])
        return np.array(pts, dtype=float), np.array(faces, dtype=np.int64)
    if path.endswith(".vtu"):
        r = vtk.vtkXMLUnstructuredGridReader()
    else:
        r = vtk.vtkGenericDataObjectReader()
    r.SetFileName(path)
    r.Update()
    out = r.GetOutput()
    pts = vtk_to_numpy(out.GetPoints().GetData()).astype(float)
    faces = []
    for c in range(out.GetNumberOfCells()):
        ids = out.GetCell(c).GetPointIds()
        faces.append([ids.GetId(k) for k in range(ids.GetNumberOfIds())])
    return pts, np.array(faces, dtype=np.int64)


def point_segment(p, a, b):
    """Distances from points p to segments a-b (arrays of shape (n, 3))."""
    e = b - a
    l2 = np.einsum("ij,ij->i", e, e)
    t = np.where(l2 > 0, np.einsum("ij,ij->i", p - a, e) / np.where(l2 > 0, l2, 1), 0)
    t = np.clip(t, 0, 1)
    return np.linalg.norm(p - (a + t[:, None] * e), axis=1)


def point_triangle(p, a, b, c):
    e1, e2, r = b - a, c - a, p - a
    m11 = np.einsum("ij,ij->i", e1, e1)
    m12 = np.einsum("ij,ij->i", e1, e2)
    m22 = np.einsum("ij,ij->i", e2, e2)
    r1 = np.einsum("ij,ij->i", e1, r)
    r2 = np.einsum("ij,ij->i", e2, r)
    det = m11 * m22 - m12 * m12
    ok = det > 1e-14 * m11 * m22
    sd = np.where(ok, det, 1)
    u = (r1 * m22 - m12 * r2) / sd
    v = (m11 * r2 - m12 * r1) / sd
    inside = ok & (u >= 0) & (v >= 0) & (u + v <= 1)
    q = a + u[:, None] * e1 + v[:, None] * e2
    d_in = np.linalg.norm(p - q, axis=1)
    d_out = np.minimum(
        np.minimum(point_segment(p, a, b), point_segment(p, b, c)), point_segment(p, c, a)
    )
    return np.where(inside, d_in, d_out)


def segment_segment(a, b, c, d):
    u, v, w = b - a, d - c, a - c
    uu = np.einsum("ij,ij->i", u, u)
    vv = np.einsum("ij,ij->i", v, v)
    uv = np.einsum("ij,ij->i", u, v)
    uw = np.einsum("ij,ij->i", u, w)
    vw = np.einsum("ij,ij->i", v, w)
    det = uu * vv - uv * uv
    ok = det > 1e-14 * uu * vv
    sd = np.where(ok, det, 1)
    s = (uv * vw - vv * uw) / sd
    t = (uu * vw - uv * uw) / sd
    inside = ok & (s > 0) & (s < 1) & (t > 0) & (t < 1)
    d_in = np.linalg.norm(w + s[:, None] * u - t[:, None] * v, axis=1)
    d_out = np.minimum(
        np.minimum(point_segment(a, c, d), point_segment(b, c, d)),
        np.minimum(point_segment(c, a, b), point_segment(d, a, b)),
    )
    return np.where(inside, d_in, d_out)


def segment_crosses(p, q, a, b, c):
    """Whether segments p-q cross triangles a-b-c (proper crossings, Möller–Trumbore).

    A segment within round-off of parallel to the triangle's plane (|det| at most 1e-12 of
    |e1| |e2| |d|, an angle below 1e-12 rad) is not counted: its u, v, t are round-off over
    round-off, and faces of one flat sheet would "cross" each other. A segment lying in an
    overlapping face is at distance 0 from it, which the distance check reports."""
    e1, e2, d = b - a, c - a, q - p
    h = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, h)
    scale = np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1) * np.linalg.norm(d, axis=1)
    ok = np.abs(det) > 1e-12 * scale
    f = 1 / np.where(ok, det, 1)
    s = p - a
    u = f * np.einsum("ij,ij->i", s, h)
    qv = np.cross(s, e1)
    v = f * np.einsum("ij,ij->i", d, qv)
    t = f * np.einsum("ij,ij->i", e2, qv)
    return ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0) & (t <= 1)


def pair_distances(x, faces, i, j, y=None, other=None):
    """Distances between faces i of (x, faces) and faces j of (y, other), by default the same
    mesh."""
    y = x if y is None else y
    other = faces if other is None else other
    fi, fj = faces[i], other[j]
    d = np.full(len(i), np.inf)
    for k in range(3):
        d = np.minimum(d, point_triangle(x[fi[:, k]], y[fj[:, 0]], y[fj[:, 1]], y[fj[:, 2]]))
        d = np.minimum(d, point_triangle(y[fj[:, k]], x[fi[:, 0]], x[fi[:, 1]], x[fi[:, 2]]))
        for m in range(3):
            d = np.minimum(
                d,
                segment_segment(
                    x[fi[:, k]], x[fi[:, (k + 1) % 3]], y[fj[:, m]], y[fj[:, (m + 1) % 3]]
                ),
            )
    return d


def components(faces, nv):
    """The connected piece of each face (faces sharing a vertex are connected)."""
    parent = list(range(nv))

    def root(v):
        while parent[v] != v:
            parent[v] = parent[parent[v]]
            v = parent[v]
        return v

    for f in faces:
        for k in (1, 2):
            a, b = root(f[0]), root(f[k])
            if a != b:
                parent[a] = b
    return np.array([root(f[0]) for f in faces])


def crossings(x, faces, i, j, y=None, other=None):
    y = x if y is None else y
    other = faces if other is None else other
    fi, fj = faces[i], other[j]
    hit = np.zeros(len(i), dtype=bool)
    for k in range(3):
        a, b = (k, (k + 1) % 3)
        hit |= segment_crosses(x[fi[:, a]], x[fi[:, b]], y[fj[:, 0]], y[fj[:, 1]], y[fj[:, 2]])
        hit |= segment_crosses(y[fj[:, a]], y[fj[:, b]], x[fi[:, 0]], x[fi[:, 1]], x[fi[:, 2]])
    return hit


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("reference")
    ap.add_argument("out")
    ap.add_argument("--exclusion", type=float)
    ap.add_argument("--obstacle")
    ap.add_argument("--translate", type=float, nargs=3, default=[0.0, 0.0, 0.0])
    ap.add_argument("--push", nargs=4, metavar=("COLUMN", "EX", "EY", "EZ"))
    ap.add_argument("--floor", type=float, default=0.0)
    ap.add_argument("--json")
    ap.add_argument("--last", action="store_true", help="check the last frame only")
    a = ap.parse_args()
    if (a.exclusion is None) == (a.obstacle is None):
        ap.error("give --exclusion (self-contact) or --obstacle (a rigid mesh)")
    x0, faces = read(a.reference)
    n = len(faces)
    y, other = None, None
    if a.obstacle:
        y, other = read(a.obstacle)
        y = y + np.array(a.translate)
        i, j = (g.ravel() for g in np.meshgrid(np.arange(n), np.arange(len(other)), indexing="ij"))
        return report(a, faces, i, j, y, other)
    i, j = np.triu_indices(n, 1)
    shared = np.zeros(len(i), dtype=bool)
    for k in range(3):
        for m in range(3):
            shared |= faces[i, k] == faces[j, m]
    i, j = i[~shared], j[~shared]
    piece = components(faces, len(x0))
    keep = (piece[i] != piece[j]) | (pair_distances(x0, faces, i, j) >= a.exclusion)
    i, j = i[keep], j[keep]
    return report(a, faces, i, j, None, None)


def report(a, faces, i, j, y, other):
    """Checks the face pairs (i, j) in every frame of a.out (module doc)."""
    frames = sorted(glob.glob(os.path.join(a.out, "frame_*.vtu")))
    if a.last:
        frames = frames[-1:]
    if not frames:
        print(f"{a.out}: no frames", file=sys.stderr)
        return 2
    offsets = {}
    if a.push:
        with open(os.path.join(a.out, "log.csv")) as f:
            rows = list(csv.DictReader(f))
        offsets = {int(r["frame"]): float(r[a.push[0]]) for r in rows}
        direction = np.array([float(c) for c in a.push[1:]])
    best = (np.inf, None, None)
    crossing = 0
    y_at = y
    for fr in frames:
        if a.push:
            number = int(os.path.basename(fr)[len("frame_") : -len(".vtu")])
            y = y_at + offsets[number] * direction
        x, fs = read(fr)
        if not np.array_equal(fs, faces):
            print(f"{fr}: the faces differ from the reference mesh's", file=sys.stderr)
            return 2
        d = pair_distances(x, faces, i, j, y, other)
        k = int(np.argmin(d)) if len(d) else None
        c = int(crossings(x, faces, i, j, y, other).sum()) if len(i) else 0
        crossing += c
        if k is not None and d[k] < best[0]:
            best = (float(d[k]), os.path.basename(fr), (int(i[k]), int(j[k])))
        dmin = float(d[k]) if k is not None else float("inf")
        print(f"{os.path.basename(fr)}: min distance {dmin:.6g}, crossing pairs {c}")
    summary = {
        "pairs": int(len(i)),
        "frames": len(frames),
        "min_distance": best[0],
        "min_frame": best[1],
        "min_faces": best[2],
        "crossing_pairs": crossing,
    }
    print(json.dumps(summary))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(summary, f)
    return 1 if crossing or best[0] < a.floor else 0


if __name__ == "__main__":
    sys.exit(main())
