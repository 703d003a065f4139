#!/usr/bin/env python3
"""Runs the balloon scenes of settings/ at full size and prints the numbers docs/balloons.md quotes.

    python3 scripts/balloon_scenes.py [sphere|accuracy|teddy|thickness|table ...] [--out DIR]

* sphere:    settings/balloon_sphere.toml, its pressure-volume curve against the closed form.
* accuracy:  neo-Hookean spheres of 642, 2562 and 10242 vertices under volume control to λ = 3,
             the worst error against p = (2μH/R)(1/λ − 1/λ⁷) and the limit point.
* teddy:     settings/balloon_teddy.toml: stretch of head, ears and body, and how far the ears
             stand out of the head, over time.
* thickness: settings/balloon_thickness.toml (the seed's element) and balloon_teddy.toml (the
             incompressible one) at 0.1, 0.2 and 0.3 mm.
* table:     seed 002's Table 1: closed shapes of 5k-30k vertices inflated at 30 frames per
             second, ms per frame, Newton iterations per frame and the skin-volume ratio, with
             the exact and the seed's position-based thickness.

Builds the release binary first. Standard library only (frames are legacy ASCII VTK, read by
scripts/vtkfield.py). Writes CSVs to scripts/results/.
"""

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import vtkfield  # noqa: E402
from paper_scenes import write_csv  # noqa: E402

BIN = os.path.join(ROOT, "target", "release", "shellsim")


def sh(args):
    subprocess.run([BIN] + args, check=True, stdout=subprocess.DEVNULL)


def run(settings, mesh, out, sets=()):
    args = [settings, mesh, "--out", out, "-q", "--overwrite"]
    for s in sets:
        args += ["--set", s]
    t = time.time()
    sh(args)
    return time.time() - t


def log(out):
    with open(os.path.join(out, "log.csv")) as f:
        return [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]


def scene(name):
    return os.path.join(ROOT, "settings", name + ".toml")


def sphere_law(rows, mu, h):
    """(λ, p, exact, relative error) per frame, λ from the discrete volume, R from V₀."""
    v0 = rows[0]["gas_volume"]
    r0 = (3 * v0 / (4 * math.pi)) ** (1 / 3)
    out = []
    for r in rows[1:]:
        lam = (r["gas_volume"] / v0) ** (1 / 3)
        exact = 2 * mu * h / r0 * (1 / lam - lam ** -7)
        out.append((lam, r["gas_pressure"], exact, r["gas_pressure"] / exact - 1))
    return out, r0


def limit_point(pts):
    """λ* and p_max from a parabola through the three highest points."""
    k = max(range(1, len(pts) - 1), key=lambda i: pts[i][1])
    (x0, y0), (x1, y1), (x2, y2) = pts[k - 1], pts[k], pts[k + 1]
    d01, d12 = (y1 - y0) / (x1 - x0), (y2 - y1) / (x2 - x1)
    a = (d12 - d01) / (x2 - x0)
    ls = 0.5 * (x0 + x1) - d01 / (2 * a)
    return ls, y1 + d12 * (ls - x1) + a * (ls - x1) * (ls - x2)


def do_sphere(out):
    print("balloon_sphere (2562 vertices, gas amount, static)")
    d = os.path.join(out, "sphere")
    wall = run(scene("balloon_sphere"), os.path.join(ROOT, "meshes/balloon_sphere.vtk"), d)
    rows = log(d)
    pts, r0 = sphere_law(rows, 0.4e6, 2e-4)
    worst = max(abs(e) for *_, e in pts)
    lam_max, p_max = max(((l, p) for l, p, *_ in pts), key=lambda t: t[1])
    print(f"  {len(pts)} equilibria to λ = {pts[-1][0]:.3f} in {wall:.1f} s; worst error "
          f"{100 * worst:.3f}%; highest pressure {p_max:.1f} Pa at λ = {lam_max:.3f} "
          f"(closed form {1.23946 * 0.4e6 * 2e-4 / r0:.1f} Pa at 1.383)")
    write_csv("balloon_sphere.csv", ["lambda", "pressure_pa", "closed_form_pa", "error"], pts)


def do_accuracy(out):
    print("neo-Hookean sphere under volume control, λ 1 → 3")
    rows_out = []
    for k in (12, 16, 32):
        edge = math.sqrt(4 * math.pi / (20 * k * k * math.sqrt(3) / 4))
        mesh = os.path.join(out, f"sphere{k}.vtk")
        sh(["mesh", "sphere", "--radius", "1", "--edge", str(edge), "-o", mesh])
        s = os.path.join(out, "nh.toml")
        with open(s, "w") as f:
            f.write('[material]\nbending = "none"\nmodel = "neo_hookean"\npoisson = 0.5\n'
                    'young = 3e6\nthickness = 0.01\n[output]\ncontinuation_frames = true\n'
                    '[gas]\ncontrol = "volume"\nvolume = %r\n[solver]\ncontinuation_step = 0.01\n'
                    'max_continuation_step = 0.025\n' % (27 * 4 / 3 * math.pi))
        d = os.path.join(out, f"nh{k}")
        wall = run(s, mesh, d)
        pts, _ = sphere_law(log(d), 1e6, 0.01)
        worst = max(abs(e) for *_, e in pts)
        ls, pm = limit_point([(l, p) for l, p, *_ in pts])
        nv = 10 * k * k + 2
        print(f"  {nv:6d} vertices: worst {100 * worst:.4f}%, λ* {ls:.4f} "
              f"({100 * (ls / 7 ** (1 / 6) - 1):+.3f}%), p_max error "
              f"{100 * (pm / (1.23946 * 1e6 * 0.01 / 1.0) - 1):+.3f}% (R₀ = 1), {wall:.1f} s")
        rows_out.append((nv, worst, ls, pm, wall))
    write_csv("balloon_accuracy.csv", ["vertices", "worst_error", "lambda_star", "p_max_pa",
                                       "wall_s"], rows_out)


R = 0.05
S = 1 / math.sqrt(2)
LOBES = {"head": ((0, 0, 0), R), "ear": ((S * R, 0, S * R), 0.38 * R),
         "ear2": ((-S * R, 0, S * R), 0.38 * R), "body": ((0, 0, -1.55 * R), 1.25 * R)}


def teddy_metrics(out):
    """Per frame: time, stretch (√ area ratio) of head, ears, body, and the ear tip's height
    above the head's equator radius, over that radius."""
    rows, region, ref_area, band = [], None, None, None
    k = 0
    times = [r["time"] for r in log(out)]
    while os.path.exists(os.path.join(out, "frame_%05d.vtk" % k)):
        pts, cells, pf, _ = vtkfield.read(os.path.join(out, "frame_%05d.vtk" % k))
        if region is None:
            ref = [tuple(p[i] - d[i] for i in range(3)) for p, d in zip(pts, pf["displacement"])]
            region = [min(LOBES, key=lambda n: math.dist(p, LOBES[n][0]) - LOBES[n][1])
                      for p in ref]
            band = [i for i, p in enumerate(ref) if region[i] == "head" and abs(p[2]) < 0.1 * R]

        def areas(P):
            a = {n: 0.0 for n in LOBES}
            for c in cells:
                rs = [region[i] for i in c]
                r = max(set(rs), key=rs.count)
                u = [P[c[1]][i] - P[c[0]][i] for i in range(3)]
                v = [P[c[2]][i] - P[c[0]][i] for i in range(3)]
                w = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
                a[r] += 0.5 * math.sqrt(sum(x * x for x in w))
            return a
        a = areas(pts)
        if ref_area is None:
            ref_area = a
        cz = sum(pts[i][2] for i in band) / len(band)
        rh = sum(math.hypot(pts[i][0], pts[i][1]) for i in band) / len(band)
        tip = max(math.dist(pts[i], (0, 0, cz)) for i in range(len(pts)) if region[i] == "ear")
        lam = {n: math.sqrt(a[n] / ref_area[n]) for n in LOBES}
        rows.append((times[k], lam["head"], lam["ear"], lam["body"], (tip - rh) / rh))
        k += 1
    return rows


def do_teddy(out):
    print("balloon_teddy (2252 vertices, dynamic)")
    d = os.path.join(out, "teddy")
    wall = run(scene("balloon_teddy"), os.path.join(ROOT, "meshes/balloon_teddy.vtk"), d,
               ["output.format=vtk_ascii"])
    m = teddy_metrics(d)
    for t, h, e, b, p in m[::5] + [m[-1]]:
        print(f"  t {t:.1f} s: stretch head {h:.3f}, ears {e:.3f}, body {b:.3f}; ears stand out "
              f"{p:.3f} of the head's radius")
    print(f"  {wall:.1f} s")
    write_csv("balloon_teddy.csv", ["time", "stretch_head", "stretch_ears", "stretch_body",
                                    "ear_protrusion"], m)


def do_thickness(out):
    print("thickness: the same air at 0.1, 0.2, 0.3 mm")
    rows = []
    for name, label in (("balloon_thickness", "seed's element (StVK, position-based)"),
                        ("balloon_teddy", "incompressible neo-Hookean")):
        for h in ("1e-4", "2e-4", "3e-4"):
            d = os.path.join(out, f"{name}_{h}")
            run(scene(name), os.path.join(ROOT, "meshes/balloon_teddy.vtk"), d,
                ["output.format=vtk_ascii", f"material.thickness={h}"])
            t, hd, e, b, p = teddy_metrics(d)[-1]
            lg = log(d)[-1]
            print(f"  {label}, {float(h) * 1e3:.1f} mm: volume {lg['gas_volume'] * 1e3:.3f} L, "
                  f"stretch head {hd:.3f}, ears {e:.3f}; ears stand out {p:.3f}; skin volume "
                  f"ratio {lg['skin_volume_ratio']:.7f}")
            rows.append((name, h, lg["gas_volume"], hd, e, b, p, lg["skin_volume_ratio"]))
    # With the atmosphere outside, the amount of air fixes the volume.
    for h in ("1e-4", "2e-4", "3e-4"):
        d = os.path.join(out, f"atmosphere_{h}")
        run(scene("balloon_teddy"), os.path.join(ROOT, "meshes/balloon_teddy.vtk"), d,
            ["output.format=vtk_ascii", f"material.thickness={h}",
             "gas.external_pressure=101325", "gas.amount=380"])
        t, hd, e, b, p = teddy_metrics(d)[-1]
        lg = log(d)[-1]
        print(f"  incompressible neo-Hookean in the atmosphere (380 J), {float(h) * 1e3:.1f} mm: "
              f"volume {lg['gas_volume'] * 1e3:.3f} L, stretch head {hd:.3f}, ears {e:.3f}")
        rows.append(("atmosphere", h, lg["gas_volume"], hd, e, b, p, lg["skin_volume_ratio"]))
    write_csv("balloon_thickness.csv", ["scene", "thickness", "volume", "stretch_head",
                                        "stretch_ears", "stretch_body", "ear_protrusion",
                                        "skin_volume_ratio"], rows)


TABLE = (  # shape, mesh arguments
    ("teddy", ["teddy", "--radius", "0.05", "--edge", "0.0026"]),
    ("peanut", ["peanut", "--radius", "0.05", "--edge", "0.0024"]),
    ("capsule", ["capsule", "--radius", "0.05", "--edge", "0.0021"]),
    ("torus", ["torus", "--radius", "0.05", "--tube", "0.02", "--edge", "0.0012"]),
    ("sphere", ["sphere", "--radius", "0.05", "--edge", "0.0014"]),
)


def do_table(out, frames):
    print(f"Table 1: {frames} frames at 30 per second, inflating from rest")
    rows = []
    for shape, margs in TABLE:
        mesh = os.path.join(out, shape + ".vtk")
        sh(["mesh"] + margs + ["-o", mesh, "--format", "vtk-ascii"])
        pts, cells, _, _ = vtkfield.read(mesh)
        vol = sum(pts[a][0] * (pts[b][1] * pts[c][2] - pts[b][2] * pts[c][1])
                  + pts[a][1] * (pts[b][2] * pts[c][0] - pts[b][0] * pts[c][2])
                  + pts[a][2] * (pts[b][0] * pts[c][1] - pts[b][1] * pts[c][0])
                  for a, b, c in cells) / 6
        for mode, sets in (("exact", []), ("seed", ["material.prism.law=\"stvk\"",
                                                    "material.prism.thickness=\"pbd\"",
                                                    "material.poisson=0.4"])):
            d = os.path.join(out, f"table_{shape}_{mode}")
            # The air of balloon_teddy.toml per unit volume of the shape (its teddy holds
            # 1.487 L at rest), pumped in over the run, a frame per step.
            end = frames / 30
            wall = run(scene("balloon_teddy"), mesh, d, sets + [
                f"time.end={end}", f"rest.dial_time={end}", "time.output_interval=0.0333333333333",
                f"gas.amount={4.1 * vol / 1.487e-3}"])
            lg = log(d)[1:]
            with open(os.path.join(d, "summary.json")) as f:
                sm = json.load(f)
            walls = [b["wall_seconds"] - a["wall_seconds"] for a, b in zip(lg, lg[1:])]
            ratio = sum(r["skin_volume_ratio"] for r in lg) / len(lg)
            ms = 1e3 * sum(walls) / len(walls)
            its = sum(r["newton_iterations"] for r in lg[1:]) / len(lg[1:])
            print(f"  {shape:8s} {mode:5s} {sm['vertices']:6d} vertices {sm['faces']:6d} faces: "
                  f"{ms:6.0f} ms/frame, {its:.1f} Newton/frame, volume ratio {ratio:.7f} "
                  f"({wall:.0f} s)")
            rows.append((shape, mode, sm["vertices"], sm["faces"], ms, its, ratio))
    write_csv("balloon_table.csv", ["shape", "thickness", "vertices", "faces", "ms_per_frame",
                                    "newton_per_frame", "volume_ratio"], rows)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("what", nargs="*",
                    default=["sphere", "accuracy", "teddy", "thickness", "table"])
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "balloon_scenes"))
    ap.add_argument("--frames", type=int, default=30)
    a = ap.parse_args()
    subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)
    os.makedirs(a.out, exist_ok=True)
    for w in a.what:
        {"sphere": lambda: do_sphere(a.out), "accuracy": lambda: do_accuracy(a.out),
         "teddy": lambda: do_teddy(a.out), "thickness": lambda: do_thickness(a.out),
         "table": lambda: do_table(a.out, a.frames)}[w]()


if __name__ == "__main__":
    main()
