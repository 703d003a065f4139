#!/usr/bin/env python3
"""The contact's two normal laws side by side: the smoothed penalty and IPC's log barrier
(`self_contact.law`), on the same scenes, with their cost and their distance from a known
answer.

    python3 scripts/contact_laws.py [--shellsim PATH] [--work DIR] [--quick]

Scenes (built here; meshes from `shellsim mesh` or written as legacy ASCII VTK):

- `stack`: three 5 cm squares (h = 1 mm, E = 1 MPa) stacked under a gravity of 1000 m/s²,
  statics. Each interface has a closed form: the penalty's penetration √(2δσ/k), the
  barrier's gap g with −k b′(g) = σ. Reported: the largest relative error of the mean
  distance between neighbouring sheets against it.
- `roll`: a 1 m × 4 cm strip (h = 1 cm) rolled by an end moment through 1.5 turns, statics,
  20 dial steps: it winds onto itself.
- `drop`: a square dropped from 1 cm onto a held one, overhanging its edge, dynamics, 0.3 s.
- `drape`: a 0.5 m disk (h = 5 mm) draped with friction μ = 0.5 over a sphere mesh (radius
  0.3 m, edges 5 cm), dynamics, 4 s (1 s with --quick).

For each: whether it converged, Newton iterations, wall time, and the smallest distance of a
gathered pair over its offset (`*_gap` in log.csv). Only the standard library is used.
"""

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def squares_vtk(path, side, n, zs):
    """Squares of side `side` with n × n cells (alternating diagonals) at heights `zs`,
    written as one legacy ASCII VTK mesh."""
    pts, tris = [], []
    for z in zs:
        base = len(pts)
        for j in range(n + 1):
            for i in range(n + 1):
                pts.append((side * i / n, side * j / n, z))
        for j in range(n):
            for i in range(n):
                a = base + j * (n + 1) + i
                b, c, d = a + 1, a + n + 1, a + n + 2
                tris += [(a, b, d), (a, d, c)] if (i + j) % 2 == 0 else [(a, b, c), (b, d, c)]
    with open(path, "w") as f:
        f.write("# vtk DataFile Version 3.0\nsquares\nASCII\nDATASET UNSTRUCTURED_GRID\n")
        f.write(f"POINTS {len(pts)} double\n")
        f.writelines(f"{x!r} {y!r} {z!r}\n" for x, y, z in pts)
        f.write(f"CELLS {len(tris)} {4 * len(tris)}\n")
        f.writelines(f"3 {a} {b} {c}\n" for a, b, c in tris)
        f.write(f"CELL_TYPES {len(tris)}\n")
        f.writelines("5\n" for _ in tris)


def ascii_points(path):
    """The points of a legacy ASCII VTK frame (`output.format = "vtk_ascii"`)."""
    with open(path) as f:
        words = f.read().split()
    i = words.index("POINTS")
    n = int(words[i + 1])
    v = [float(w) for w in words[i + 3 : i + 3 + 3 * n]]
    return [v[3 * k : 3 * k + 3] for k in range(n)]


def barrier_gap(sigma, k, g_hat):
    """The gap g in (0, ĝ) where −k b′(g) = σ, b IPC's log barrier (bisection)."""
    lo, hi = 0.0, g_hat
    for _ in range(200):
        g = 0.5 * (lo + hi)
        u, l = g - g_hat, math.log(g / g_hat)
        if -k * (-2.0 * u * l - u * u / g) > sigma:
            lo = g
        else:
            hi = g
    return 0.5 * (lo + hi)


def run(shellsim, cwd, toml, mesh, out, law, extra=()):
    args = [shellsim, toml, mesh, "--out", out, "-q", "--overwrite",
            "--set", f'self_contact.law="{law}"', *extra]
    t0 = time.perf_counter()
    res = subprocess.run(args, cwd=cwd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    with open(os.path.join(cwd, out, "summary.json")) as f:
        summary = json.load(f)
    with open(os.path.join(cwd, out, "log.csv")) as f:
        rows = list(csv.DictReader(f))
    gaps = [float(r[c]) for r in rows for c in r if c.endswith("_gap") and not c.startswith("obstacle")]
    return {
        "converged": summary.get("converged") and res.returncode == 0,
        "newton": summary.get("newton_iterations"),
        "wall": wall,
        "gap": min(gaps) if gaps else float("nan"),
        "summary": summary,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--shellsim", default=os.path.join(ROOT, "target/release/shellsim"))
    ap.add_argument("--work", default="contact_laws_work")
    ap.add_argument("--quick", action="store_true", help="a 1 s drape")
    a = ap.parse_args()
    shellsim = os.path.abspath(a.shellsim)
    work = os.path.abspath(a.work)
    os.makedirs(work, exist_ok=True)
    mesh = lambda *args: subprocess.run([shellsim, "mesh", *args], cwd=work, check=True,
                                        capture_output=True)
    h = 1e-3
    squares_vtk(os.path.join(work, "stack.vtk"), 0.05, 5, [k * 1.001 * h for k in range(3)])
    with open(os.path.join(work, "stack.toml"), "w") as f:
        f.write(f"""[material]\nyoung = 1e6\nthickness = {h}\ndensity = 1000
[loads]\ngravity = [0, 0, -1000]
[constraints]\nfix_boxes = [{{ min = [-1, -1, -1e-4], max = [1, 1, 1e-4] }}]
[[constraints.support]]\ncomponents = ["x", "y"]\ninside = {{ min = [-1, -1, 5e-4], max = [1, 1, 1] }}
[output]\nformat = "vtk_ascii"
[self_contact]\nenabled = true
""")
    mesh("rectangle", "--lx", "1", "--ly", "0.04", "--edge", "0.02", "-o", "strip.vtk")
    with open(os.path.join(work, "roll.toml"), "w") as f:
        f.write(f"""[material]\nyoung = 1e7\npoisson = 0.0\nthickness = 0.01
[solver]\nsymmetry_breaking = 0.0\ncontinuation_step = 0.05
[output]\ncontinuation_frames = true
[[constraints.clamp]]\ninside = {{ min = [-1, -1, -1], max = [-0.499, 1, 1] }}
[[loads.moment]]\nmoment = {2.5 * math.pi}\ninside = {{ min = [0.499, -1, -1], max = [1, 1, 1] }}
[self_contact]\nenabled = true
""")
    squares_vtk(os.path.join(work, "drop.vtk"), 0.05, 5, [0.0])
    # The dropped square: the same, shifted to overhang and 1 cm up (appended to the mesh).
    squares_vtk(os.path.join(work, "top.vtk"), 0.05, 5, [0.01])
    with open(os.path.join(work, "drop.vtk")) as f:
        low = f.read().split("\n")
    with open(os.path.join(work, "top.vtk")) as f:
        top = f.read().split("\n")

    def parts(lines):
        i = next(k for k, l in enumerate(lines) if l.startswith("POINTS"))
        n = int(lines[i].split()[1])
        j = next(k for k, l in enumerate(lines) if l.startswith("CELLS"))
        m = int(lines[j].split()[1])
        return lines[i + 1 : i + 1 + n], lines[j + 1 : j + 1 + m]

    (p0, c0), (p1, c1) = parts(low), parts(top)
    p1 = [" ".join(repr(float(v) + d) for v, d in zip(l.split(), (0.003, 0.002, 0.0))) for l in p1]
    n0 = len(p0)
    c1 = ["3 " + " ".join(str(int(v) + n0) for v in l.split()[1:]) for l in c1]
    with open(os.path.join(work, "drop.vtk"), "w") as f:
        f.write("# vtk DataFile Version 3.0\ndrop\nASCII\nDATASET UNSTRUCTURED_GRID\n")
        f.write(f"POINTS {n0 + len(p1)} double\n" + "\n".join(p0 + p1) + "\n")
        f.write(f"CELLS {len(c0) + len(c1)} {4 * (len(c0) + len(c1))}\n")
        f.write("\n".join(c0 + c1) + "\n")
        f.write(f"CELL_TYPES {len(c0) + len(c1)}\n" + "5\n" * (len(c0) + len(c1)))
    with open(os.path.join(work, "drop.toml"), "w") as f:
        f.write(f"""[material]\nyoung = 1e6\nthickness = {h}\ndensity = 1000
[solver]\nmode = "dynamic"
[time]\nend = 0.3\ndt = 1e-3\noutput_interval = 0.01
[loads]\ngravity = [0, 0, -9.81]
[constraints]\nfix_boxes = [{{ min = [-1, -1, -1e-4], max = [1, 1, 1e-4] }}]
[self_contact]\nenabled = true
""")
    mesh("disk", "--radius", "0.5", "--edge", "0.05", "-o", "disk.vtk")
    mesh("sphere", "--radius", "0.3", "--edge", "0.05", "-o", "ball.vtk")
    with open(os.path.join(work, "drape.toml"), "w") as f:
        f.write(f"""[material]\nyoung = 1e6\npoisson = 0.3\nthickness = 0.005\ndensity = 1000
[solver]\nmode = "dynamic"
[time]\nend = {1 if a.quick else 4}\ndt = 1e-3\ndt_max = 0.05\noutput_interval = 1\ndamping = 0.05
[loads]\ngravity = [0, 0, -9.81]
[[obstacles]]\nshape = "mesh"\nfile = "ball.vtk"\ntranslate = [0, 0, -0.3026]\nfriction = 0.5
""")

    print(f"{'scene':8} {'law':8} {'conv':5} {'newton':>7} {'wall s':>8} {'min d/ξ':>9}  error")
    results = {}
    for scene, m in [("stack", "stack.vtk"), ("roll", "strip.vtk"), ("drop", "drop.vtk"),
                     ("drape", "disk.vtk")]:
        for law in ["penalty", "barrier"]:
            r = run(shellsim, work, f"{scene}.toml", m, f"{scene}_{law}", law)
            err = ""
            if scene == "stack" and r["converged"]:
                x = ascii_points(os.path.join(work, f"stack_{law}", r["summary"]["final_frame"]))
                n = len(x) // 3
                z = [sum(p[2] for p in x[k * n : (k + 1) * n]) / n for k in range(3)]
                k_pen, delta = 1e6 / h, h / 100
                worst = 0.0
                for upper, carried in [(1, 2.0), (2, 1.0)]:
                    sigma = carried * 1000 * h * 1000
                    exact = (-barrier_gap(sigma, k_pen, delta) if law == "barrier"
                             else math.sqrt(2 * delta * sigma / k_pen))
                    pen = h - (z[upper] - z[upper - 1])
                    worst = max(worst, abs(pen - exact) / abs(exact))
                err = f"{100 * worst:.2f}% of the closed form"
            results[(scene, law)] = r
            print(f"{scene:8} {law:8} {str(bool(r['converged'])):5} {r['newton']!s:>7} "
                  f"{r['wall']:8.2f} {r['gap']:9.4f}  {err}", flush=True)
    return 0 if all(r["converged"] for r in results.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
