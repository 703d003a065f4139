#!/usr/bin/env python3
"""Runs the structural benchmarks that docs/benchmarks.md quotes and prints their numbers.

    python3 scripts/structural_benchmarks.py [roof|cost|scordelis|balloons ...] [--out DIR]

* roof:      the hinged cylindrical roof's snap-through (Sze, Liu & Lo 2004, problem 3.8) by
             arc length on 24², 34² and 48² grids of the full roof: the load's maximum and
             minimum (P/P_ref, and the centre deflection W there), against 0.7421 / 11.29 mm
             and 0.1729 / 19.85 mm, with the Richardson extrapolation and the wall times.
* cost:      the same roof on 48² under 1.5 kN (a monotone path), by load control and by arc
             length with about the same dial steps, every step a frame solved to the full
             tolerance, on 1 thread: seconds per step and their ratio (three runs each).
* scordelis: the Scordelis–Lo roof (MacNeal & Harder 1985) with rigid diaphragms, linearised
             (gravity × 1e-3, the deflection × 1e3): the vertical deflection at the middle of a
             free edge against 0.3024, the whole roof on 32² and 48² grids and the quarter
             model (symmetry planes x = 0, y = 0) on 16², 32² and 48².
* pinched:   the pinched cylinder with rigid diaphragms (R 300, L 600, t 3, E 3e6, ν 0.3), the
             octant model with three symmetry planes, the deflection under the load times
             E t / P against 164.24 (1.82488e-5 at P = 1), on uniform 24², 48², 64² and 96²
             grids and on 32², 48² and 64² grids graded toward the load (power 1.35).
* hemisphere: the pinched hemisphere with an 18° hole (R 10, t 0.04, E 6.825e7, ν 0.3), the
             quarter model, the load point's displacement against 0.094, on 16² to 64².
* balloons:  neo-Hookean and Mooney–Rivlin (c₂/c₁ = 0.1) spheres of 642 and 2562 vertices by
             arc length under pressure control: worst error against the thin-sphere law and
             the turning points.

Uses target/release/shellsim (or $SHELLSIM_BIN); build it first. Standard library only. Writes
scripts/results/structural_benchmarks.csv.
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
BIN = os.environ.get("SHELLSIM_BIN", os.path.join(ROOT, "target", "release", "shellsim"))


def run(args, cwd):
    subprocess.run([BIN] + args, check=True, cwd=cwd, stdout=subprocess.DEVNULL)


def grid_triangles(n, m):
    """The triangles of an (n + 1) × (m + 1) grid of points (row-major), each quad split along
    alternating diagonals."""
    tris = []
    for j in range(m):
        for i in range(n):
            a = j * (n + 1) + i
            b, c, d = a + 1, a + n + 1, a + n + 2
            tris += [(a, b, d), (a, d, c)] if (i + j) % 2 == 0 else [(a, b, c), (b, d, c)]
    return tris


def write_vtk(path, title, pts, tris):
    """Points and triangles as legacy ASCII VTK."""
    with open(path, "w") as f:
        f.write(f"# vtk DataFile Version 3.0\n{title}\nASCII\nDATASET POLYDATA\n")
        f.write(f"POINTS {len(pts)} double\n")
        for p in pts:
            f.write("%.17g %.17g %.17g\n" % p)
        f.write(f"POLYGONS {len(tris)} {4 * len(tris)}\n")
        for t in tris:
            f.write("3 %d %d %d\n" % t)


def cylinder_patch(path, radius, trange, yrange, n, m, drop, gamma=1.0):
    """A cylinder patch about the y axis, angle θ in `trange` (from +z towards +x), y in
    `yrange`, n × m quads split along alternating diagonals; z lowered by `drop`; with `gamma`
    other than 1 the grid is graded toward (trange[0], yrange[0]), θ and y varying as the
    `gamma`-th power of the grid coordinate (legacy ASCII VTK)."""
    pts = []
    for j in range(m + 1):
        for i in range(n + 1):
            t = trange[0] + (trange[1] - trange[0]) * (i / n) ** gamma
            y = yrange[0] + (yrange[1] - yrange[0]) * (j / m) ** gamma
            pts.append((radius * math.sin(t), y, radius * math.cos(t) - drop))
    write_vtk(path, "patch", pts, grid_triangles(n, m))


def log(out):
    with open(os.path.join(out, "log.csv")) as f:
        return [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]


def summary(out):
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


def at_arc(rows, column, s):
    """`column` at path coordinate s: the parabola through the three nearest frames."""
    k = min(range(1, len(rows) - 1), key=lambda i: abs(rows[i]["arc_length"] - s))
    p = [(rows[i]["arc_length"], rows[i][column]) for i in (k - 1, k, k + 1)]
    out = 0.0
    for i in range(3):
        w = 1.0
        for j in range(3):
            if j != i:
                w *= (s - p[j][0]) / (p[i][0] - p[j][0])
        out += w * p[i][1]
    return out


ROOF = """[material]
thickness = 0.0127
young = 3.10275e9
poisson = 0.3
[[loads.point]]
force = [0, 0, -{p}]
inside = {{ min = [-1e-6, -1e-6, -1], max = [1e-6, 1e-6, 1] }}
[[constraints.support]]
components = ["x", "y", "z"]
inside = {{ min = [-1, -1, -1e-9], max = [1, 1, 1e-9] }}
[solver]
continuation = "{c}"
"""


def roof(out, rows_out):
    refs = {"load_maximum": (0.7421, 11.29), "load_minimum": (0.1729, 19.85)}
    found = {}
    for n in (24, 34, 48):
        mesh = os.path.join(out, f"roof{n}.vtk")
        cylinder_patch(mesh, 2.54, (-0.1, 0.1), (-0.254, 0.254), n, n, 2.54 * math.cos(0.1))
        with open(os.path.join(out, "roof.toml"), "w") as f:
            f.write(ROOF.format(p=3000, c="arc_length"))
        d = os.path.join(out, f"roof{n}")
        t0 = time.time()
        run(["roof.toml", mesh, "--out", d, "-q", "--overwrite"], out)
        wall = time.time() - t0
        s, rows = summary(d), log(d)
        for c in s["arc_length"]["critical_points"]:
            if c["kind"] not in refs:
                continue
            w = 1000 * at_arc(rows, "point_load_displacement", c["arc_length"])
            found.setdefault(c["kind"], []).append((n, c["dial"], w))
            ref = refs[c["kind"]]
            print(f"roof {n}² ({2 * n * n} faces): {c['kind']} P/P_ref {c['dial']:.4f} "
                  f"({100 * (c['dial'] / ref[0] - 1):+.2f}%), W {w:.2f} mm (ref {ref[1]}), "
                  f"{s['arc_length']['steps']} steps, {s['newton_iterations']} iterations, "
                  f"{wall:.1f} s")
            rows_out.append(["roof", n, 2 * n * n, c["kind"], c["dial"], ref[0], w, ref[1],
                             wall])
    for kind, v in found.items():
        (n1, p1, _), (n2, p2, _) = v[-2], v[-1]
        r = (n2 / n1) ** 2
        ext = p2 + (p2 - p1) / (r - 1)
        print(f"roof {kind}: Richardson (second order) from {n1}², {n2}²: {ext:.4f} "
              f"(ref {refs[kind][0]}, {100 * (ext / refs[kind][0] - 1):+.2f}%)")


def cost(out, rows_out):
    n = 48
    mesh = os.path.join(out, f"roof{n}.vtk")
    cylinder_patch(mesh, 2.54, (-0.1, 0.1), (-0.254, 0.254), n, n, 2.54 * math.cos(0.1))
    settings = {
        "load": ROOF.format(p=1500, c="load") + "continuation_step = 0.1\nmax_continuation_step = 0.1\n"
        "[output]\ncontinuation_frames = true\n",
        "arc_length": ROOF.format(p=1500, c="arc_length") + "arc_length_step = 0.1414\n"
        "max_arc_length_step = 0.1414\n",
    }
    per = {}
    for c, text in settings.items():
        with open(os.path.join(out, f"{c}.toml"), "w") as f:
            f.write(text)
        best = []
        for _ in range(3):
            d = os.path.join(out, f"cost_{c}")
            run([f"{c}.toml", mesh, "--out", d, "-q", "--overwrite", "--threads", "1"], out)
            s = summary(d)
            best.append((s["wall_seconds"] / s["steps"], s["steps"], s["newton_iterations"]))
        per[c] = min(best)
        print(f"cost {c}: {per[c][0]:.4f} s per step ({per[c][1]} steps, "
              f"{per[c][2]} Newton iterations), best of 3")
    ratio = per["arc_length"][0] / per["load"][0]
    print(f"cost: arc length / load control per step = {ratio:.2f}")
    rows_out.append(["cost", n, 2 * n * n, "ratio per step", ratio, 1.3, "", "", ""])


SCORDELIS = """[material]
thickness = 0.25
young = 4.32e8
poisson = 0.0
density = 360
[loads]
gravity = [0, 0, -0.001]
[[constraints.support]]
components = ["x", "z"]
inside = { min = [-30, -25.001, -30], max = [30, -24.999, 30] }
[[constraints.support]]
components = ["x", "z"]
inside = { min = [-30, 24.999, -30], max = [30, 25.001, 30] }
[[constraints.support]]
components = ["y"]
inside = { min = [-30, -0.001, -30], max = [30, 0.001, 30] }
"""


def final_displacements(d):
    sys.path.insert(0, HERE)
    import vtkfield  # noqa: E402
    x, _, pf, _ = vtkfield.read(os.path.join(d, summary(d)["final_frame"]))
    return x, pf["displacement"]


def scordelis(out, rows_out):
    r, th = 25.0, math.radians(40)
    quarter = SCORDELIS.split("[[constraints.support]]")[0] + (
        '[[constraints.support]]\ncomponents = ["x", "z"]\n'
        "inside = { min = [-30, 24.999, -30], max = [30, 25.001, 30] }\n"
        '[[constraints.symmetry]]\naxis = "x"\n[[constraints.symmetry]]\naxis = "y"\n')
    cases = [("whole", SCORDELIS, (-th, th), (-25.0, 25.0), n) for n in (32, 48)]
    cases += [("quarter", quarter, (0.0, th), (0.0, 25.0), n) for n in (16, 32, 48)]
    for model, text, trange, yrange, n in cases:
        with open(os.path.join(out, "sl.toml"), "w") as f:
            f.write(text)
        mesh = os.path.join(out, f"sl_{model}{n}.vtk")
        cylinder_patch(mesh, r, trange, yrange, n, n, 0.0)
        d = os.path.join(out, f"sl_{model}{n}")
        t0 = time.time()
        run(["sl.toml", mesh, "--out", d, "-q", "--overwrite", "--set",
             'output.format="vtk_ascii"'], out)
        wall = time.time() - t0
        x, u = final_displacements(d)
        k = min(range(len(x)), key=lambda i: (x[i][0] - u[i][0] - r * math.sin(th)) ** 2
                + (x[i][1] - u[i][1]) ** 2)
        w = -1000 * u[k][2]
        print(f"Scordelis–Lo {model} {n}² ({2 * n * n} faces): {w:.4f} "
              f"({100 * (w / 0.3024 - 1):+.2f}%), {wall:.2f} s")
        rows_out.append([f"scordelis_lo_{model}", n, 2 * n * n, "deflection", w, 0.3024, "", "",
                         wall])


PINCHED = """[material]
thickness = 3.0
young = 3e6
poisson = 0.3
[[loads.point]]
force = [0, 0, -250]
inside = { min = [-1e-6, -1e-6, 299], max = [1e-6, 1e-6, 301] }
[[constraints.support]]
components = ["x", "z"]
inside = { min = [-400, 299.999, -400], max = [400, 300.001, 400] }
[[constraints.symmetry]]
axis = "x"
[[constraints.symmetry]]
axis = "y"
[[constraints.symmetry]]
axis = "z"
"""


def pinched(out, rows_out):
    with open(os.path.join(out, "pc.toml"), "w") as f:
        f.write(PINCHED)
    for n, gamma in ((24, 1.0), (48, 1.0), (64, 1.0), (96, 1.0), (32, 1.35), (48, 1.35),
                     (64, 1.35)):
        mesh = os.path.join(out, f"pc{n}_{gamma}.vtk")
        cylinder_patch(mesh, 300.0, (0.0, math.pi / 2), (0.0, 300.0), n, n, 0.0, gamma)
        d = os.path.join(out, f"pc{n}_{gamma}")
        t0 = time.time()
        run(["pc.toml", mesh, "--out", d, "-q", "--overwrite", "--set",
             'output.format="vtk_ascii"'], out)
        wall = time.time() - t0
        _, u = final_displacements(d)
        # The load point (θ = 0, y = 0) is vertex 0; the octant carries P/4 of P = 1000 (a
        # linear response: w ≈ 0.018 against t = 3; a load of 1e-3 would sit near the
        # gradient's round-off on this stiff shell).
        w = -u[0][2] / 1e3
        grid = "uniform" if gamma == 1.0 else f"graded {gamma}"
        print(f"pinched cylinder octant {n}² {grid} ({2 * n * n} faces): {w:.5e} "
              f"({100 * (w / 1.82488e-5 - 1):+.2f}%), {wall:.2f} s")
        rows_out.append([f"pinched_cylinder_{'uniform' if gamma == 1.0 else 'graded'}", n,
                         2 * n * n, "deflection", w, 1.82488e-5, "", "", wall])


HEMISPHERE = """[material]
thickness = 0.04
young = 6.825e7
poisson = 0.3
[[loads.point]]
force = [0.001, 0, 0]
inside = { min = [9.999, -1e-6, -1e-6], max = [10.001, 1e-6, 1e-6] }
[[loads.point]]
force = [0, -0.001, 0]
inside = { min = [-1e-6, 9.999, -1e-6], max = [1e-6, 10.001, 1e-6] }
[[constraints.symmetry]]
axis = "x"
[[constraints.symmetry]]
axis = "y"
[[constraints.support]]
components = ["z"]
inside = { min = [7.0, 7.0, -1e-6], max = [7.1, 7.1, 1e-6] }
"""


def hemisphere_quarter(path, n, r=10.0, hole=math.radians(18)):
    """The quarter of the pinched hemisphere on an n × n grid of azimuth and polar angle,
    oriented outward (legacy ASCII VTK)."""
    pts = []
    for j in range(n + 1):
        for i in range(n + 1):
            al = hole + (math.pi / 2 - hole) * j / n
            be = (math.pi / 2) * i / n
            pts.append((r * math.sin(al) * math.cos(be), r * math.sin(al) * math.sin(be),
                        r * math.cos(al)))
    # The grid's triangles reversed: the polar angle grows downwards.
    tris = [(a, c, b) for (a, b, c) in grid_triangles(n, n)]
    write_vtk(path, "hemisphere", pts, tris)


def hemisphere(out, rows_out):
    with open(os.path.join(out, "hs.toml"), "w") as f:
        f.write(HEMISPHERE)
    for n in (16, 24, 32, 48, 64):
        mesh = os.path.join(out, f"hs{n}.vtk")
        hemisphere_quarter(mesh, n)
        d = os.path.join(out, f"hs{n}")
        t0 = time.time()
        run(["hs.toml", mesh, "--out", d, "-q", "--overwrite", "--set",
             'output.format="vtk_ascii"'], out)
        wall = time.time() - t0
        _, u = final_displacements(d)
        w = 1000 * u[n * (n + 1)][0]
        print(f"pinched hemisphere quarter {n}² ({2 * n * n} faces): {w:.5f} "
              f"({100 * (w / 0.094 - 1):+.2f}%), {wall:.2f} s")
        rows_out.append(["pinched_hemisphere", n, 2 * n * n, "deflection", w, 0.094, "", "",
                         wall])


def balloons(out, rows_out):
    planes = "".join(
        f'[[constraints.support]]\ncomponents = ["{c}"]\ninside = {{ min = {lo}, max = {hi} }}\n'
        for c, lo, hi in (("x", "[-1e-9, -2, -2]", "[1e-9, 2, 2]"),
                          ("y", "[-2, -1e-9, -2]", "[2, 1e-9, 2]"),
                          ("z", "[-2, -2, -1e-9]", "[2, 2, 1e-9]")))
    cases = {
        "neo_hookean": ('model = "neo_hookean"\npoisson = 0.5\nyoung = 3e6', 2e4, 40,
                        lambda l: 2e6 * (1 / l - l ** -7)),
        "mooney_rivlin": ('model = "mooney_rivlin"\nc1 = 5e5\nc2 = 5e4', 1.6e4, 400,
                          lambda l: 4 * (5e5 + 5e4 * l * l) * (1 / l - l ** -7)),
    }
    for k in (8, 16):
        edge = math.sqrt(4 * math.pi / (20 * k * k * math.sqrt(3) / 4))
        mesh = os.path.join(out, f"sphere{k}.vtk")
        run(["mesh", "sphere", "--radius", "1", "--edge", str(edge), "-o", mesh], out)
        for name, (mat, p, steps, law) in cases.items():
            with open(os.path.join(out, f"{name}.toml"), "w") as f:
                f.write(f'[material]\nbending = "none"\nthickness = 0.01\n{mat}\n[gas]\n'
                        f'control = "pressure"\npressure = {p}\n[solver]\n'
                        f'continuation = "arc_length"\nmax_arc_length_steps = {steps}\n'
                        + planes)
            d = os.path.join(out, f"{name}{k}")
            t0 = time.time()
            run([f"{name}.toml", mesh, "--out", d, "-q", "--overwrite"], out)
            wall = time.time() - t0
            rows, s = log(d), summary(d)
            v0 = rows[0]["gas_volume"]
            r0 = (3 * v0 / (4 * math.pi)) ** (1 / 3)
            lam = [(r["gas_volume"] / v0) ** (1 / 3) for r in rows[1:]]
            worst = max(abs(r["gas_pressure"] / (0.01 / r0 * law(lv)) - 1)
                        for r, lv in zip(rows[1:], lam))
            turns = []
            for c in s["arc_length"]["critical_points"]:
                if c["kind"] != "bifurcation":
                    lc = (at_arc(rows, "gas_volume", c["arc_length"]) / v0) ** (1 / 3)
                    turns.append(f"{c['kind']} p {c['dial'] * p:.1f} Pa at λ {lc:.4f}")
            print(f"{name} {10 * k * k + 2} vertices: worst {100 * worst:.3f}% out to "
                  f"λ {lam[-1]:.2f}; {'; '.join(turns)}; {len(rows) - 1} steps, {wall:.1f} s")
            rows_out.append([name, 10 * k * k + 2, 20 * k * k, "worst", worst, 5e-3, lam[-1],
                             "", wall])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("which", nargs="*", default=["roof", "cost", "scordelis", "pinched",
                                                 "hemisphere", "balloons"])
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "structural_benchmarks"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows = []
    for w in a.which:
        {"roof": roof, "cost": cost, "scordelis": scordelis, "pinched": pinched,
         "hemisphere": hemisphere, "balloons": balloons}[w](a.out, rows)
    # The results file keeps the rows of the problems not run this time.
    prefixes = {"roof": "roof", "cost": "cost", "scordelis": "scordelis",
                "pinched": "pinched_cylinder", "hemisphere": "pinched_hemisphere",
                "balloons": "balloon"}
    ran = tuple(prefixes[w] for w in a.which)
    path = os.path.join(HERE, "results", "structural_benchmarks.csv")
    kept = []
    if os.path.exists(path):
        with open(path) as f:
            kept = [r for r in list(csv.reader(f))[1:] if r and not r[0].startswith(ran)]
    os.makedirs(os.path.join(HERE, "results"), exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["case", "grid", "faces", "quantity", "value", "reference", "w_or_lambda",
                    "w_reference", "wall_seconds"])
        w.writerows(sorted(kept + rows, key=lambda r: r[0]))


if __name__ == "__main__":
    main()
