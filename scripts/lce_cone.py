"""The liquid-crystal-elastomer cone under refinement: a disk with a circumferential director
(settings/lce_cone.toml) against the closed form sin(alpha) = lambda^(1+nu) and the rim's
perimeter 2 pi lambda R. Standard library only.

    python3 scripts/lce_cone.py [--bin target/release/shellsim] [--mode static|explicit]

Writes scripts/results/lce_cone.csv (edge, faces, half-angle, error in degrees, rim ratio,
wall seconds)."""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(__file__))
import vtkfield  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LAMBDA, NU = 0.9, 0.5


def half_angle(ref, x, r_min=0.4):
    """Half-angle (degrees) of the cone through the vertices of reference radius >= r_min: the
    axis is the rim polygon's normal (Newell), the distance from the axis is fitted linearly in
    the height along it; the slope is tan(alpha), whatever the apex does."""
    rim = [v for v in range(len(x)) if math.hypot(ref[v][0], ref[v][1]) > 1 - 1e-9]
    rim.sort(key=lambda v: math.atan2(ref[v][1], ref[v][0]))
    n = [0.0, 0.0, 0.0]
    for i, v in enumerate(rim):
        a, b = x[v], x[rim[(i + 1) % len(rim)]]
        n[0] += (a[1] - b[1]) * (a[2] + b[2])
        n[1] += (a[2] - b[2]) * (a[0] + b[0])
        n[2] += (a[0] - b[0]) * (a[1] + b[1])
    ln = math.sqrt(sum(c * c for c in n))
    n = [c / ln for c in n]
    c = [sum(x[v][k] for v in rim) / len(rim) for k in range(3)]
    sh = sr = shh = shr = m = 0.0
    for v in range(len(x)):
        if math.hypot(ref[v][0], ref[v][1]) < r_min:
            continue
        d = [x[v][k] - c[k] for k in range(3)]
        h = sum(d[k] * n[k] for k in range(3))
        rho = math.sqrt(max(sum(d[k] ** 2 for k in range(3)) - h * h, 0.0))
        sh += h
        sr += rho
        shh += h * h
        shr += h * rho
        m += 1
    slope = (m * shr - sh * sr) / (m * shh - sh * sh)
    ratio = sum(
        math.dist(x[rim[i]], x[rim[(i + 1) % len(rim)]]) for i in range(len(rim))
    ) / sum(math.dist(ref[rim[i]], ref[rim[(i + 1) % len(rim)]]) for i in range(len(rim)))
    return math.degrees(math.atan(abs(slope))), ratio


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default=os.path.join(ROOT, "target/release/shellsim"))
    ap.add_argument("--mode", default="static")
    ap.add_argument("--edges", default="0.12,0.083,0.06,0.045")
    args = ap.parse_args()
    exact = math.degrees(math.asin(LAMBDA ** (1 + NU)))
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for edge in [float(e) for e in args.edges.split(",")]:
            mesh = os.path.join(d, f"disk{edge}.vtk")
            subprocess.run([args.bin, "mesh", "disk", "--radius", "1", "--edge", str(edge),
                            "-o", mesh], check=True, capture_output=True)
            out = os.path.join(d, f"o{edge}")
            sets = ["--set", "output.format=vtk_ascii", "--set", f"solver.mode={args.mode}"]
            if args.mode == "explicit":
                sets += ["--set", "material.bending=patch_fit"]
            subprocess.run([args.bin, os.path.join(ROOT, "settings/lce_cone.toml"), mesh,
                            "--out", out, "-q"] + sets, check=True)
            s = json.load(open(os.path.join(out, "summary.json")))
            ref = vtkfield.read(os.path.join(out, "frame_00000.vtk"))[0]
            x = vtkfield.read(os.path.join(out, s["final_frame"]))[0]
            a, r = half_angle(ref, x)
            rows.append((edge, s["faces"], a, a - exact, r, s["wall_seconds"]))
            print(f"edge {edge}: {s['faces']} faces, half-angle {a:.4f} deg "
                  f"(exact {exact:.4f}, error {a - exact:+.4f}), rim ratio {r:.6f}, "
                  f"{s['wall_seconds']:.2f} s")
    os.makedirs(os.path.join(ROOT, "scripts/results"), exist_ok=True)
    with open(os.path.join(ROOT, f"scripts/results/lce_cone_{args.mode}.csv"), "w") as f:
        f.write("edge,faces,half_angle_deg,error_deg,rim_ratio,wall_seconds\n")
        for r in rows:
            f.write(",".join(str(v) for v in r) + "\n")


if __name__ == "__main__":
    main()
