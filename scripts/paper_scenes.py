#!/usr/bin/env python3
"""Runs the environment-driven scenes of settings/ at full size and prints the numbers docs/scenes.md quotes.

    python3 scripts/paper_scenes.py [strip|annulus|disk|cap|walker ...] [--out DIR]

Builds the release binary first. Standard library only (frames are legacy ASCII VTK, read by
scripts/vtkfield.py). Writes one CSV per scene to scripts/results/.
"""

import argparse
import cmath
import csv
import math
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import vtkfield  # noqa: E402

BIN = os.path.join(ROOT, "target", "release", "shellsim")


def run(scene, mesh, out, sets=()):
    args = [BIN, os.path.join(ROOT, "settings", scene + ".toml"), os.path.join(ROOT, mesh),
            "--out", out, "-q", "--set", "output.format=vtk_ascii"]
    for s in sets:
        args += ["--set", s]
    t = time.time()
    subprocess.run(args, check=True)
    return time.time() - t


def frames(out):
    k = 0
    while os.path.exists(os.path.join(out, "frame_%05d.vtk" % k)):
        yield vtkfield.read(os.path.join(out, "frame_%05d.vtk" % k))
        k += 1


def mean(v):
    v = list(v)
    return sum(v) / max(len(v), 1)


def curl(cf):
    return mean(max(abs(a[0]), abs(b[0])) for a, b in zip(cf["k1"], cf["k2"]))


def write_csv(name, header, rows):
    os.makedirs(os.path.join(HERE, "results"), exist_ok=True)
    path = os.path.join(HERE, "results", name)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)
    print("  wrote", os.path.relpath(path, ROOT))


def strip(out):
    mu, mu_perp, nu, h = 0.02, 0.06, 0.3, 1e-4
    for scene in ("paper_strip_md", "paper_strip_cd"):
        o = os.path.join(out, scene)
        wall = run(scene, "meshes/paper_strip.vtk", o)
        rows = []
        for k, (p, c, pf, cf) in enumerate(frames(o)):
            xs = [q[0] for q in p]
            mt, mb = mean(a[0] for a in cf["moisture_top"]), mean(a[0] for a in cf["moisture_bottom"])
            rows.append((round(0.1 * k, 6), curl(cf), (mu_perp + nu * mu) * (mt - mb) / h,
                         max(xs) - min(xs), mt, mb))
        write_csv(scene + ".csv", ["time", "curl", "curl_formula", "extent_x", "m_top", "m_bottom"], rows)
        peak = max(rows, key=lambda r: r[1])
        tenth = next((r[0] for r in rows if r[0] > peak[0] and r[1] < 0.1 * peak[1]), None)
        half = next((r[0] for r in rows if r[0] > peak[0] and r[1] < 0.5 * peak[1]), None)
        print(f"{scene}: peak curl {peak[1]:.1f} 1/m at {peak[0]:.1f} s "
              f"(formula (μ⊥+νμ)Δm/h {peak[2]:.1f}, {100 * (peak[1] / peak[2] - 1):+.1f}%), "
              f"half at {half} s, 10% at {tenth} s; smallest x-extent {min(r[3] for r in rows) * 1e3:.1f} mm; "
              f"at 1, 5, 10, 20 s: {[round(rows[i][1], 1) for i in (10, 50, 100, 200) if i < len(rows)]}; "
              f"wall {wall:.1f} s")


def rim_modes(p0, p):
    r_out = max(math.hypot(q[0], q[1]) for q in p0)
    rim = [i for i, q in enumerate(p0) if math.hypot(q[0], q[1]) > 0.999 * r_out]
    th = [math.atan2(p0[i][1], p0[i][0]) for i in rim]
    cx, cy = mean(p[i][0] for i in rim), mean(p[i][1] for i in rim)
    r = [math.hypot(p[i][0] - cx, p[i][1] - cy) for i in rim]
    rm = mean(r)
    amps = [abs(sum((rr - rm) * cmath.exp(-1j * n * t) for rr, t in zip(r, th))) / len(r)
            for n in range(13)]
    n = max(range(2, 13), key=lambda k: amps[k])
    return n, amps[n]


def annulus(out):
    for h in ("5.0e-5", "1.0e-4", "2.0e-4"):
        o = os.path.join(out, "annulus_" + h)
        wall = run("paper_annulus", "meshes/paper_annulus.vtk", o, [f"material.thickness={h}"])
        fr = list(frames(o))
        p0 = fr[0][0]
        rows = [(round(0.1 * k, 6),) + rim_modes(p0, f[0]) for k, f in enumerate(fr) if k > 0]
        write_csv(f"paper_annulus_{h}.csv", ["time", "n", "amplitude"], rows)
        seq = []
        for r in rows:
            if r[2] > 5e-5 and (not seq or seq[-1][0] != r[1]):
                seq.append((r[1], r[0]))
        print(f"annulus h = {h} m: dominant rim mode (n, from t) {seq}; max n "
              f"{max((r[1] for r in rows if r[2] > 5e-5), default=0)}; wall {wall:.1f} s")


def disk(out):
    o = os.path.join(out, "gel_disk")
    wall = run("gel_disk_hyperbolic", "meshes/gel_disk.vtk", o)
    fr = list(frames(o))
    p0, c = fr[0][0], fr[0][1]
    k = fr[-1][3]["gauss_curvature"]
    rows = []
    for frac in (0.25, 0.5, 0.75, 0.9):
        sel = [i for i, f in enumerate(c)
               if math.hypot(mean(p0[v][0] for v in f), mean(p0[v][1] for v in f)) < frac * 0.03]
        rows.append((frac, mean(k[i][0] for i in sel) * 0.03 ** 2))
    write_csv("gel_disk_hyperbolic.csv", ["r_over_R", "K_rho2"], rows)
    print(f"gel disk: K ρ² (target −1) within r < {[(f, round(v, 4)) for f, v in rows]}; wall {wall:.1f} s")


def cap(out):
    rows = []
    for h in ("0.02", "0.01", "0.005", "0.0025"):
        o = os.path.join(out, "cap_" + h)
        wall = run("conformal_cap", "meshes/unit_disk.vtk", o, [f"material.thickness={h}"])
        e = subprocess.run([BIN, "error", "conformal_cap", os.path.join(o, "frame_00001.vtk")],
                           check=True, capture_output=True, text=True).stdout
        import json
        e = json.loads(e)
        rows.append((h, e["hausdorff_rel"], e["rms_error_rel"], wall))
    write_csv("conformal_cap.csv", ["thickness", "hausdorff_rel", "rms_rel", "wall_s"], rows)
    print("conformal cap (b̄ = 0): " + ", ".join(f"h = {r[0]}: Hausdorff {100 * r[1]:.2f}%" for r in rows))


def tips_of(rows):
    """Tips of the walker: the centre (column 2) first swinging past ±12 mm (a fifth of the
    length), then past 5 mm on the other side, alternately. Returns (time, centre mm) pairs."""
    tips, side = [], None
    for r in rows:
        x = r[2] - rows[0][2]
        bound = 0.012 if side is None else 0.005
        if abs(x) > bound and (side is None or (x > 0) != side):
            side = x > 0
            tips.append((r[0], round(1e3 * x, 1)))
    return tips


def walker(out):
    o = os.path.join(out, "walker")
    wall = run("paper_walker", "meshes/paper_walker.vtk", o)
    rows = []
    for k, (p, c, pf, cf) in enumerate(frames(o)):
        down = 0
        for f in c:
            a, b, cc = (p[i] for i in f)
            nz = (b[0] - a[0]) * (cc[1] - a[1]) - (b[1] - a[1]) * (cc[0] - a[0])
            down += nz < 0
        rows.append((round(0.1 * k, 6), max(q[2] for q in p), mean(q[0] for q in p), down / len(c),
                     mean(a[0] for a in cf["moisture_bottom"]), mean(a[0] for a in cf["moisture_top"])))
    write_csv("paper_walker.csv", ["time", "z_max", "x_mean", "turned_over", "m_bottom", "m_top"], rows)
    peak = max(rows, key=lambda r: r[3])
    tips = tips_of(rows)
    print(f"walker: highest point {max(r[1] for r in rows) * 1e3:.1f} mm; most faces turned over "
          f"{100 * peak[3]:.0f}% at {peak[0]} s; tips (time s, centre mm) {tips}; wall {wall:.1f} s")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scenes", nargs="*", default=["strip", "annulus", "disk", "cap", "walker"])
    ap.add_argument("--out", default="/tmp/shellsim_paper_scenes")
    a = ap.parse_args()
    subprocess.run(["cargo", "build", "--release", "-q"], cwd=ROOT, check=True)
    for s in a.scenes:
        globals()[s](os.path.join(a.out))


if __name__ == "__main__":
    main()
