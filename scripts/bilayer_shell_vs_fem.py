#!/usr/bin/env python3
"""The shell against the volumetric reference: a free bilayer strip (20 × 1 × 1 mm, equal layers,
E = 1 MPa, ν = 0.3) whose top layer swells by ε more than its bottom, solved by shellsim (growth
law "bilayer", with and without isotropic_layers, both membrane models) and by
scripts/bilayer_fem.py (3D, triquadratic hexahedra, large deformation, neo-Hookean and St
Venant–Kirchhoff). Prints a table of the curvature of the deformed mid-surface, κh, and the
shell's error, also over (κH)², H the grown thickness: the Koiter model drops the metric's
quadratic term in the height, so its error should scale with (κH)².

    bilayer_shell_vs_fem.py [--shellsim PATH] [--fem-results DIR] [--out table.md]

The FEM numbers are read from DIR/bilayer_fem_{neo_hookean,svk}.jsonl (written by
`bilayer_fem.py --sweep [--material svk]`); without them the sweeps are run (about a minute
each).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MISMATCH = [0.05, 0.10, 0.20, 0.35, 0.50]


def circle_fit(p):
    """Centre and radius of the least-squares circle (Kåsa's algebraic fit) through 3D points
    in their best-fit plane."""
    c0 = p.mean(0)
    _, _, vt = np.linalg.svd(p - c0)
    q = np.c_[(p - c0) @ vt[0], (p - c0) @ vt[1]]
    a = np.c_[q, np.ones(len(q))]
    d, e, f = np.linalg.lstsq(a, -(q ** 2).sum(1), rcond=None)[0]
    c = np.array([-d / 2, -e / 2])
    return c0 + c[0] * vt[0] + c[1] * vt[1], np.sqrt(c @ c - f)


def shell_curvature(run):
    """κ of the deformed centre line over the middle half, positive when the strip bulges
    toward its top (the normal side)."""
    s = json.load(open(os.path.join(run, "summary.json")))
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(os.path.join(run, s["final_frame"]))
    r.Update()
    o = r.GetOutput()
    x = vtk_to_numpy(o.GetPoints().GetData()).astype(float)
    ref = x - vtk_to_numpy(o.GetPointData().GetArray("displacement"))
    length = ref[:, 0].max() - ref[:, 0].min()
    on = np.where((np.abs(ref[:, 1]) < 1e-9) & (np.abs(ref[:, 0]) <= length / 4 + 1e-12))[0]
    centre, radius = circle_fit(x[on])
    cells = vtk_to_numpy(o.GetCells().GetConnectivityArray()).reshape(-1, 3)
    mid = on[np.argmin(np.abs(ref[on, 0]))]
    f = cells[np.any(cells == mid, axis=1)][0]
    normal = np.cross(x[f[1]] - x[f[0]], x[f[2]] - x[f[0]])
    return -np.sign((centre - x[mid]) @ normal) / radius, s["converged"]


def fem_results(folder, material):
    path = os.path.join(folder, f"bilayer_fem_{material.replace('-', '_')}.jsonl")
    if not os.path.exists(path):
        env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
        out = subprocess.run(
            [sys.executable, os.path.join(ROOT, "scripts/bilayer_fem.py"), "--sweep",
             "--material", material],
            check=True, capture_output=True, text=True, env=env).stdout
        with open(path, "w") as fh:
            fh.write(out)
    rows = [json.loads(line) for line in open(path) if line.strip()]
    return {round(r["inputs"]["eps_top"], 6): -r["kappa_mid_h"] for r in rows}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--shellsim", default=os.path.join(ROOT, "target/release/shellsim"))
    ap.add_argument("--fem-results", default=os.path.join(ROOT, "scripts/results"))
    ap.add_argument("--out")
    a = ap.parse_args()
    fem = {m: fem_results(a.fem_results, m) for m in ["neo-hookean", "svk"]}
    h = 1e-3
    lines = ["| ε | FEM neo-Hookean κh | FEM SVK κh | shell model | layers | shell κh | "
             "error vs neo-Hookean | / (κH)² | error vs SVK | / (κH)² |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    with tempfile.TemporaryDirectory() as d:
        subprocess.run([a.shellsim, "mesh", "rectangle", "--lx", "0.02", "--ly", "0.001",
                        "--edge", "0.00025", "-o", "strip.vtk"], cwd=d, check=True,
                       capture_output=True)
        for eps in MISMATCH:
            for model in ["koiter", "neo_hookean"]:
                for iso in ["true", "false"]:
                    name = f"{model}_{iso}_{eps}"
                    with open(os.path.join(d, name + ".toml"), "w") as fh:
                        fh.write(f"[material]\nyoung = 1e6\npoisson = 0.3\nthickness = {h}\n"
                                 f"model = \"{model}\"\n[growth]\nlaw = \"bilayer\"\n"
                                 f"mu_top = {eps}\nmu_bottom = 0\nmoisture_top = 1\n"
                                 f"moisture_bottom = 1\nisotropic_layers = {iso}\n")
                    subprocess.run([a.shellsim, name + ".toml", "strip.vtk", "--out", name, "-q"],
                                   cwd=d, check=True, capture_output=True)
                    k, converged = shell_curvature(os.path.join(d, name))
                    grown = h * (1 + eps / 2) if iso == "true" else h
                    row = [f"{eps:.2f}", f"{fem['neo-hookean'][eps]:.5f}", f"{fem['svk'][eps]:.5f}",
                           model, "isotropic" if iso == "true" else "kept thickness",
                           f"{k * h:.5f}" + ("" if converged else " (not converged)")]
                    for m in ["neo-hookean", "svk"]:
                        ref = fem[m][eps] / h
                        err = k / ref - 1
                        row += [f"{err:+.2%}", f"{err / (ref * grown) ** 2:+.3f}"]
                    lines.append("| " + " | ".join(row) + " |")
    text = "\n".join(lines) + "\n"
    print(text, end="")
    if a.out:
        with open(a.out, "w") as fh:
            fh.write(text)


if __name__ == "__main__":
    main()
