#!/usr/bin/env python3
"""How the scene build (reading the settings and the mesh, building and checking the scene)
grows with the mesh: the curvature-programmed cone of settings/gcm_cone.toml on meshes of about
10k and 40k faces (and more with --faces), the build time from summary.json's timing.build.

Exits 1 when the build grows faster than about n log n between the first two sizes: more than
1.5 × (n₂ log n₂)/(n₁ log n₁), 7× for 10k → 40k; a quadratic build would take 16×. The build is
timed three times per mesh and the fastest kept (the machine is shared).

Uses target/release/shellsim (or $SHELLSIM_BIN); build it first. Standard library only. Writes
scripts/results/build_scaling.csv.
"""

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
BIN = os.environ.get("SHELLSIM_BIN", os.path.join(ROOT, "target", "release", "shellsim"))
SETTINGS = os.path.join(ROOT, "settings", "gcm_cone.toml")
# The cone's sector, as in the settings' header: 1 ≤ r ≤ 1.4, 2π sin(atan 2) rad.
SWEEP = 360.0 * math.sin(math.atan(2.0))
AREA = math.radians(SWEEP) / 2.0 * (1.4 ** 2 - 1.0)


def cone(path, faces):
    """A jittered cone mesh of about `faces` faces (edge from the area of equilateral faces)."""
    edge = math.sqrt(4.0 * AREA / (math.sqrt(3.0) * faces))
    subprocess.run([BIN, "mesh", "annulus", "--inner", "1", "--radius", "1.4", "--sweep",
                    str(SWEEP), "--edge", str(edge), "--jitter", "0.25", "--program", "gcm_cone",
                    "-o", path], check=True, stdout=subprocess.DEVNULL)


def build_seconds(mesh, out):
    """The fastest of three runs' timing.build, and the run's face count."""
    best = math.inf
    for _ in range(3):
        subprocess.run([BIN, SETTINGS, mesh, "--out", out, "-q", "--overwrite", "--threads",
                        "1"], check=True)
        with open(os.path.join(out, "summary.json")) as f:
            s = json.load(f)
        best = min(best, s["timing"]["build"])
    with open(os.path.join(out, "run.json")) as f:
        faces = json.load(f)["runs"][-1]["faces"]
    return best, faces


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--faces", type=int, nargs="*", default=[10000, 40000])
    a = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in a.faces:
            mesh = os.path.join(tmp, f"cone{n}.vtk")
            cone(mesh, n)
            t, faces = build_seconds(mesh, os.path.join(tmp, f"out{n}"))
            rows.append((faces, t))
            print(f"{faces} faces: build {t:.3f} s, {1e6 * t / faces:.2f} µs per face")
    os.makedirs(os.path.join(HERE, "results"), exist_ok=True)
    with open(os.path.join(HERE, "results", "build_scaling.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["faces", "build_seconds"])
        w.writerows(rows)
    (n1, t1), (n2, t2) = rows[0], rows[1]
    allowed = 1.5 * (n2 * math.log(n2)) / (n1 * math.log(n1))
    print(f"build ratio {t2 / t1:.2f} for {n2 / n1:.2f}× the faces (allowed {allowed:.2f})")
    if t2 / t1 > allowed:
        print("the build grows faster than n log n", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
