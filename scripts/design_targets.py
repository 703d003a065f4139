"""Writes the targets of the example designs in designs/ from a flat disk mesh.

    python3 scripts/design_targets.py vase DISK.vtk OUT.vtk [--height H]
    python3 scripts/design_targets.py saddle DISK.vtk OUT.vtk [--curvature C]
    python3 scripts/design_targets.py helix STRIP.vtk OUT.vtk [--radius R] [--angle DEG]
    python3 scripts/design_targets.py cap DISK.vtk OUT.vtk [--radius R] [--area A]

* `vase`: a surface of revolution with a flat bottom, a bulge, a neck and a flared lip,
  reached from the unit disk by its conformal map: with the profile (R(σ), Z(σ)) by arc length
  σ from the pole, the disk's radius ρ maps to σ(ρ) with dσ/dρ = R(σ)/ρ (so that
  dσ² + R² dφ² = e^{2s}(dρ² + ρ² dφ²), e^s = R/ρ), scaled so that the rim ρ = 1 is the lip.
  Each disk vertex (ρ, φ) goes to (R(σ) cos φ, R(σ) sin φ, Z(σ)): the target has the disk's
  connectivity, and the growth that makes it is isotropic; no closed form gives it.
* `saddle`: the disk's vertices lifted onto z = C (x² − y²) (the target of a surface design:
  its in-plane positions are not those of any growth).

* `helix`: a flat strip along x (centred on the origin) wrapped onto a cylinder of radius R
  about the y axis turned by the angle DEG: each vertex (x, y) goes to the point at arc length
  u = x cos α + y sin α around the cylinder and height v = −x sin α + y cos α along its axis, an
  isometry (the strip's metric is kept; its curvature is 1/R along the turned direction), so the
  strip's long edges become helices.

* `cap`: a spherical cap of radius R whose area is A times the unit disk's (a liquid-crystal
  sheet's actuated area is λ^(1−ν) times its own: A = 0.9487 for λ = 0.9, ν = 0.5): each disk
  vertex (ρ, φ) goes to polar angle ρ t₁ on the sphere, cos t₁ = 1 − A/(2R²) (the target of a
  surface design: its in-plane positions are not those of the design's).

Needs the project's virtual environment (`vtk`, `numpy`).
"""

import argparse
import math
import sys

import numpy as np
import vtk
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy


def read(path):
    r = vtk.vtkGenericDataObjectReader() if path.endswith(".vtk") else vtk.vtkXMLGenericDataObjectReader()
    r.SetFileName(path)
    r.Update()
    return r.GetOutput()


def write(data, points, path):
    out = vtk.vtkPolyData()
    pts = vtk.vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(points), deep=True))
    out.SetPoints(pts)
    cells = vtk.vtkCellArray()
    for i in range(data.GetNumberOfCells()):
        c = data.GetCell(i)
        cells.InsertNextCell(3, [c.GetPointId(k) for k in range(3)])
    out.SetPolys(cells)
    w = vtk.vtkPolyDataWriter()
    w.SetFileName(path)
    w.SetFileVersion(42)
    w.SetInputData(out)
    if not w.Write():
        sys.exit(f"{path}: cannot write")


def vase_profile(height, n=20000):
    """The generating curve (R, Z) sampled by arc length: a flat bottom to R = 0.5, a rounded
    heel, a wall that bulges, narrows to a neck and flares to a lip."""
    t = np.linspace(0.0, 1.0, n)
    # The wall's radius against its height fraction u ∈ [0, 1].
    def wall(u):
        return 0.62 + 0.08 * np.sin(math.pi * u) - 0.14 * np.sin(math.pi * u) ** 2 + 0.12 * u**3

    heel = 0.12
    pts = []
    for x in t:
        if x < 0.4:  # bottom
            pts.append((0.5 * x / 0.4, 0.0))
        elif x < 0.55:  # heel: a quarter turn of radius `heel` joined to the wall's foot
            a = (x - 0.4) / 0.15 * (math.pi / 2)
            pts.append((0.5 + heel * math.sin(a), heel * (1 - math.cos(a))))
        else:
            u = (x - 0.55) / 0.45
            pts.append((0.5 + heel + (wall(u) - wall(0.0)), heel + height * u))
    p = np.array(pts)
    sigma = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    return sigma, p[:, 0], p[:, 1]


def vase(disk, height):
    x = vtk_to_numpy(disk.GetPoints().GetData()).astype(float)
    sigma, R, Z = vase_profile(height)
    # ln ρ(σ) = ln σ₁ + ∫_{σ₁}^{σ} dσ/R from a first sample on the flat bottom (where R = σ).
    i1 = 1
    lnrho = np.zeros_like(sigma)
    lnrho[i1:] = math.log(sigma[i1]) + np.concatenate(
        [[0.0], np.cumsum(np.diff(sigma[i1:]) / (0.5 * (R[i1:-1] + R[i1 + 1 :])))]
    )
    lnrho[:i1] = -np.inf
    lnrho -= lnrho[-1]  # the lip at ρ = 1
    rho = np.hypot(x[:, 0], x[:, 1])
    phi = np.arctan2(x[:, 1], x[:, 0])
    out = np.zeros_like(x)
    for k, r in enumerate(rho):
        if r == 0.0:
            continue
        s = np.interp(math.log(min(r, 1.0)), lnrho[i1:], sigma[i1:])
        rr, zz = np.interp(s, sigma, R), np.interp(s, sigma, Z)
        out[k] = (rr * math.cos(phi[k]), rr * math.sin(phi[k]), zz)
    return out


def saddle(disk, c):
    x = vtk_to_numpy(disk.GetPoints().GetData()).astype(float).copy()
    x[:, 2] = c * (x[:, 0] ** 2 - x[:, 1] ** 2)
    return x


def helix(strip, radius, angle):
    x = vtk_to_numpy(strip.GetPoints().GetData()).astype(float)
    a = math.radians(angle)
    u = x[:, 0] * math.cos(a) + x[:, 1] * math.sin(a)
    v = -x[:, 0] * math.sin(a) + x[:, 1] * math.cos(a)
    out = np.zeros_like(x)
    out[:, 0] = radius * np.sin(u / radius)
    out[:, 1] = v
    out[:, 2] = radius * (1.0 - np.cos(u / radius))
    return out


def cap(disk, radius, area):
    x = vtk_to_numpy(disk.GetPoints().GetData()).astype(float)
    c = 1.0 - area / (2.0 * radius**2)
    if not -1.0 < c < 1.0:
        sys.exit(f"no cap of radius {radius} has area {area}π")
    t = np.hypot(x[:, 0], x[:, 1]) * math.acos(c)
    phi = np.arctan2(x[:, 1], x[:, 0])
    return np.c_[radius * np.sin(t) * np.cos(phi), radius * np.sin(t) * np.sin(phi), radius * (1.0 - np.cos(t))]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("shape", choices=["vase", "saddle", "helix", "cap"])
    ap.add_argument("disk")
    ap.add_argument("out")
    ap.add_argument("--height", type=float, default=0.45)
    ap.add_argument("--curvature", type=float, default=0.3)
    ap.add_argument("--radius", type=float, default=0.5)
    ap.add_argument("--angle", type=float, default=30.0)
    ap.add_argument("--area", type=float, default=1.0)
    a = ap.parse_args()
    disk = read(a.disk)
    if disk is None or disk.GetNumberOfCells() == 0:
        sys.exit(f"{a.disk}: no faces")
    if a.shape == "vase":
        pts = vase(disk, a.height)
    elif a.shape == "saddle":
        pts = saddle(disk, a.curvature)
    elif a.shape == "helix":
        pts = helix(disk, a.radius, a.angle)
    else:
        pts = cap(disk, a.radius, a.area)
    write(disk, pts, a.out)
    print(f"{a.out}: {a.shape}, {disk.GetNumberOfPoints()} vertices, {disk.GetNumberOfCells()} faces")


if __name__ == "__main__":
    main()
