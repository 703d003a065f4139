"""The inverse-design examples at full size, each designed from the command line and its written
design run forward the way a user would, with the numbers the docs quote:

* `cap`: the stereographic cap (designs/cap_forward.toml's growth s = ln(2/(1 + r²))) designed
  back from s = 0 on 3072 faces (designs/cap.toml): distance, iterations, time, and the designed
  s against the true one (RMS, relative);
* `vase`, `saddle`, `helix`: designs/vase.toml, designs/saddle.toml, designs/helix.toml on their
  targets from scripts/design_targets.py;
* `lc_cap`: designs/lc_cap.toml, a liquid-crystal disk made a spherical cap: the actuated
  sheet's best-fit sphere and the designed director against the closed-form spiral of Warner &
  Mostajeran (Proc. R. Soc. A 2018) for r > 0.2.

For every design: the distance to the target the design reports, and the forward run of the
written design (`shellsim DIR/settings.toml DIR/designed.vtk`) against the target, measured
here: by a Kabsch fit over the vertices (unweighted) when the target has the mesh's
connectivity, else the design's own forward check (surface to surface).

    .venv/bin/python scripts/design_numbers.py [--bin target/release/shellsim] [CASE ...]

Writes scripts/results/design_numbers.csv (case, faces, iterations, seconds, design distance,
forward distance RMS and max over the target's size, and a case's own check). Needs the
project's virtual environment (vtk, numpy). About 4 minutes on 2 cores.
"""

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np
from vtk.util.numpy_support import vtk_to_numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from design_targets import read  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TARGETS = os.path.join(ROOT, "scripts", "design_targets.py")
LAMBDA, NU = 0.9, 0.5


def points(data):
    return vtk_to_numpy(data.GetPoints().GetData()).astype(float)


def centroids(data):
    x = points(data)
    cells = np.array([[data.GetCell(i).GetPointId(k) for k in range(3)] for i in range(data.GetNumberOfCells())])
    return x[cells].mean(axis=1)


def cell_field(data, name):
    return vtk_to_numpy(data.GetCellData().GetArray(name)).astype(float)


def kabsch(x, y):
    """RMS and largest distance of x to y after the best rotation and translation, over y's
    bounding-box diagonal (unweighted)."""
    xc, yc = x - x.mean(axis=0), y - y.mean(axis=0)
    u, _, vt = np.linalg.svd(xc.T @ yc)
    d = np.sign(np.linalg.det(u @ vt))
    e = np.linalg.norm(xc @ (u @ np.diag([1.0, 1.0, d]) @ vt) - yc, axis=1)
    size = np.linalg.norm(y.max(axis=0) - y.min(axis=0))
    return math.sqrt((e**2).mean()) / size, e.max() / size


def sphere_fit(x):
    """Radius of the least-squares sphere through x, and x's RMS distance from it over x's
    bounding-box diagonal."""
    a = np.c_[2.0 * x, np.ones(len(x))]
    c = np.linalg.lstsq(a, (x**2).sum(axis=1), rcond=None)[0]
    r = math.sqrt(c[3] + c[:3] @ c[:3])
    d = np.linalg.norm(x - c[:3], axis=1) - r
    return r, math.sqrt((d**2).mean()) / np.linalg.norm(x.max(axis=0) - x.min(axis=0))


def cap_director(r, radius, n=4000):
    """The director's angle to the radius that makes the nematic sheet a sphere of `radius`:
    u = √C, C = λ² sin²α + λ^(−2ν) cos²α, solves r u' = (λ^(1−ν)/u)√(1 − r²u²/R²) − u from
    u(0)² = λ^(1−ν) (RK4)."""
    c0 = LAMBDA ** (1.0 - NU)

    def f(x, u):
        return 0.0 if x == 0.0 else ((c0 / u) * math.sqrt(max(0.0, 1.0 - (x * u / radius) ** 2)) - u) / x

    h, u = r / n, math.sqrt(c0)
    for i in range(n):
        x = i * h
        k1 = f(x, u)
        k2 = f(x + h / 2, u + h / 2 * k1)
        k3 = f(x + h / 2, u + h / 2 * k2)
        k4 = f(x + h, u + h * k3)
        u += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    lo, hi = LAMBDA**2, LAMBDA ** (-2.0 * NU)
    return math.asin(math.sqrt(min(1.0, max(0.0, (hi - u * u) / (hi - lo)))))


class Runner:
    def __init__(self, binary, work):
        self.bin, self.work = binary, work

    def sh(self, *args):
        r = subprocess.run(args, cwd=self.work, capture_output=True, text=True)
        return r.returncode, r.stdout + r.stderr

    def ok(self, *args):
        code, out = self.sh(*args)
        if code != 0:
            sys.exit(f"{' '.join(args)}: exit {code}\n{out}")
        return out

    def mesh(self, name, *args):
        self.ok(self.bin, "mesh", *args, "-o", name)
        return read(os.path.join(self.work, name))

    def target(self, shape, src, out, *args):
        self.ok(sys.executable, TARGETS, shape, src, out, *args)

    def design(self, design, mesh, target, out):
        code, text = self.sh(self.bin, "design", design, mesh, target, "--out", out, "--overwrite", "-q")
        if code not in (0, 1):
            sys.exit(f"design {design}: exit {code}\n{text}")
        with open(os.path.join(self.work, out, "design_summary.json")) as f:
            return json.load(f)

    def forward(self, out):
        self.ok(self.bin, f"{out}/settings.toml", f"{out}/designed.vtk", "--out", f"{out}_forward", "-q")
        with open(os.path.join(self.work, f"{out}_forward", "summary.json")) as f:
            s = json.load(f)
        return read(os.path.join(self.work, f"{out}_forward", s["final_frame"]))


def design_row(case, s, faces):
    fc = s.get("forward_check", {})
    return {
        "case": case,
        "faces": faces,
        "iterations": s["iterations"],
        "seconds": round(s["wall_seconds"], 1),
        "distance": f"{s['distance']:.3e}",
        "reproduces": fc.get("reproduces", ""),
        "forward_rms": f"{fc['distance']:.3e}" if "distance" in fc else "",
        "forward_max": "",
        "check": "",
        "value": "",
    }


def cap(r):
    disk = r.mesh("cap_disk.vtk", "disk", "--radius", "1", "--edge", "0.045")
    r.ok(r.bin, os.path.join(ROOT, "designs", "cap_forward.toml"), "cap_disk.vtk", "--out", "cap_target", "-q")
    s = r.design(os.path.join(ROOT, "designs", "cap.toml"), "cap_disk.vtk", "cap_target/frame_00001.vtu", "cap_design")
    row = design_row("cap", s, disk.GetNumberOfCells())
    fwd = r.forward("cap_design")
    tgt = read(os.path.join(r.work, "cap_target", "frame_00001.vtu"))
    row["forward_rms"], row["forward_max"] = (f"{v:.3e}" for v in kabsch(points(fwd), points(tgt)))
    c = centroids(disk)
    s_true = np.log(2.0 / (1.0 + (c[:, :2] ** 2).sum(axis=1)))
    s_des = cell_field(read(os.path.join(r.work, "cap_design", "designed.vtk")), "growth_factor")
    row["check"] = "s RMS relative error"
    row["value"] = f"{math.sqrt(((s_des - s_true) ** 2).mean() / (s_true**2).mean()):.3e}"
    return row


def same_mesh_case(r, case, mesh_args, shape, shape_args):
    m = r.mesh(f"{case}_mesh.vtk", *mesh_args)
    r.target(shape, f"{case}_mesh.vtk", f"{case}_target.vtk", *shape_args)
    s = r.design(os.path.join(ROOT, "designs", f"{case}.toml"), f"{case}_mesh.vtk", f"{case}_target.vtk", f"{case}_design")
    row = design_row(case, s, m.GetNumberOfCells())
    fwd = r.forward(f"{case}_design")
    tgt = read(os.path.join(r.work, f"{case}_target.vtk"))
    rms, mx = kabsch(points(fwd), points(tgt))
    if case == "saddle":
        # A surface target: the vertices' in-plane positions are not the design's.
        row["check"], row["value"] = "vertex Kabsch RMS (not the objective)", f"{rms:.3e}"
    else:
        row["forward_rms"], row["forward_max"] = f"{rms:.3e}", f"{mx:.3e}"
    return row


def lc_cap(r):
    disk = r.mesh("lc_disk.vtk", "disk", "--radius", "1", "--edge", "0.08")
    r.target("cap", "lc_disk.vtk", "lc_target.vtk", "--radius", "2.5", "--area", f"{LAMBDA ** (1 - NU)!r}")
    s = r.design(os.path.join(ROOT, "designs", "lc_cap.toml"), "lc_disk.vtk", "lc_target.vtk", "lc_design")
    row = design_row("lc_cap", s, disk.GetNumberOfCells())
    radius, off = sphere_fit(points(r.forward("lc_design")))
    designed = read(os.path.join(r.work, "lc_design", "designed.vtk"))
    theta = cell_field(designed, "abar_info")[:, 0]
    c = centroids(designed)
    rr, phi = np.hypot(c[:, 0], c[:, 1]), np.arctan2(c[:, 1], c[:, 0])
    keep = rr > 0.2
    exact = np.array([cap_director(x, 2.5) for x in rr[keep]])
    e = np.mod(theta[keep] - phi[keep] - exact + math.pi / 2, math.pi) - math.pi / 2
    row["check"] = "sphere radius (2.5) / off-sphere RMS / director RMS deg (r > 0.2)"
    row["value"] = f"{radius:.4f} / {off:.2e} / {math.degrees(math.sqrt((e**2).mean())):.2f}"
    return row


CASES = {
    "cap": cap,
    "vase": lambda r: same_mesh_case(r, "vase", ["disk", "--radius", "1", "--edge", "0.08"], "vase", []),
    "saddle": lambda r: same_mesh_case(r, "saddle", ["disk", "--radius", "1", "--edge", "0.1"], "saddle", ["--curvature", "0.3"]),
    "helix": lambda r: same_mesh_case(
        r, "helix", ["rectangle", "--lx", "4", "--ly", "0.4", "--edge", "0.1"], "helix", ["--radius", "0.5", "--angle", "30"]
    ),
    "lc_cap": lc_cap,
}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", default=os.path.join(ROOT, "target", "release", "shellsim"))
    ap.add_argument("cases", nargs="*", choices=[[]] + list(CASES), default=[])
    a = ap.parse_args()
    binary = os.path.abspath(a.bin)
    if not os.path.exists(binary):
        sys.exit(f"{binary}: no such binary (cargo build --release, or give --bin)")
    rows = []
    with tempfile.TemporaryDirectory() as work:
        r = Runner(binary, work)
        for case in a.cases or list(CASES):
            row = CASES[case](r)
            print(", ".join(f"{k} {v}" for k, v in row.items() if v != ""), flush=True)
            rows.append(row)
    out = os.path.join(ROOT, "scripts", "results", "design_numbers.csv")
    with open(out, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
