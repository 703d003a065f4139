#!/usr/bin/env python3
"""Convergence study of the bending models.

Every bending model x mesh kind (regular, Delaunay of random points, jittered by 25% of the
edge length) x case (cylinder, Gauss-Codazzi-Mainardi cone, spherical cap, bilayer strip) x
3-4 resolutions, through the real command line: `shellsim mesh ... --program CASE`, a static
solve, and `shellsim error CASE FRAME`. Writes one CSV row per run, then prints the observed
orders and a markdown table (the one in docs/accuracy.md).

    scripts/convergence_study.py [--out CSV] [--threads N] [--quick] [--table-only]

`--quick` runs the two coarsest resolutions only. `--table-only` re-reads an existing CSV.
Columns: model, mesh, case, edge, vertices, faces, threads, converged, newton_iterations,
wall_seconds, max_error_rel, rms_error_rel.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODELS = ["midedge_average", "patch_fit", "midedge_sin", "midedge_tan"]
KINDS = ["regular", "delaunay", "jittered"]
GCM_SWEEP_DEG = 360.0 * 2.0 / math.sqrt(5.0)  # 2*pi*sin(atan 2), in degrees

# case -> (shape arguments, edge lengths)
CASES = {
    "cylinder": (["square"], [0.1, 0.05, 0.025, 0.0125]),
    "gcm_cone": (
        ["annulus", "--inner", "1", "--radius", "1.4", "--sweep", repr(GCM_SWEEP_DEG)],
        [0.08, 0.04, 0.02],
    ),
    "spherical_cap": (["square"], [0.1, 0.05, 0.025]),
    "bilayer_strip": (["rectangle", "--lx", "1", "--ly", "0.1"], [0.02, 0.01, 0.005]),
}
FIELDS = [
    "model", "mesh", "case", "edge", "vertices", "faces", "threads", "converged",
    "newton_iterations", "wall_seconds", "max_error_rel", "rms_error_rel",
]


def run(cmd, **kw):
    return subprocess.run(cmd, check=False, capture_output=True, text=True, **kw)


def study(out, threads, quick):
    subprocess.run(
        ["cargo", "build", "--release", "--quiet", "--manifest-path", os.path.join(ROOT, "Cargo.toml")],
        check=True,
    )
    exe = os.path.join(ROOT, "target", "release", "shellsim")
    rows = []
    with tempfile.TemporaryDirectory() as work, open(out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=FIELDS)
        w.writeheader()
        for case, (shape, edges) in CASES.items():
            for kind in KINDS:
                for edge in edges[:2] if quick else edges:
                    mesh = os.path.join(work, "m.vtk")
                    extra = {"regular": [], "delaunay": ["--delaunay", "--seed", "7"],
                             "jittered": ["--jitter", "0.25", "--seed", "7"]}[kind]
                    r = run([exe, "mesh", *shape, "--edge", str(edge), "--program", case, *extra, "-o", mesh])
                    if r.returncode != 0:
                        sys.exit(f"mesh generation failed: {r.stderr}")
                    for model in MODELS:
                        settings = os.path.join(work, "s.toml")
                        with open(settings, "w") as s:
                            s.write(f'[material]\nthickness = 0.01\nbending = "{model}"\n'
                                    '[rest]\ntarget = "mesh"\n')
                        o = os.path.join(work, f"o-{model}")
                        run([exe, settings, mesh, "--out", o, "--threads", str(threads), "-q"])
                        summ = json.load(open(os.path.join(o, "summary.json")))
                        err = json.loads(run([exe, "error", case, os.path.join(o, summ["final_frame"])]).stdout)
                        row = {
                            "model": model, "mesh": kind, "case": case, "edge": edge,
                            "vertices": summ["vertices"], "faces": summ["faces"],
                            "threads": summ["threads"], "converged": summ["converged"],
                            "newton_iterations": summ["newton_iterations"],
                            "wall_seconds": round(summ["wall_seconds"], 3),
                            "max_error_rel": err["max_error_rel"], "rms_error_rel": err["rms_error_rel"],
                        }
                        w.writerow(row)
                        fh.flush()
                        rows.append(row)
                        print(",".join(str(row[k]) for k in FIELDS), flush=True)
    return rows


def orders(rows):
    """Observed order of the max error between successive resolutions: log(e1/e2)/log(h1/h2),
    with h ~ 1/sqrt(faces)."""
    groups = {}
    for r in rows:
        groups.setdefault((r["case"], r["mesh"], r["model"]), []).append(r)
    out = {}
    for key, rs in groups.items():
        rs.sort(key=lambda r: int(r["faces"]))
        ps = []
        for a, b in zip(rs, rs[1:]):
            ea, eb = float(a["max_error_rel"]), float(b["max_error_rel"])
            ha, hb = 1 / math.sqrt(int(a["faces"])), 1 / math.sqrt(int(b["faces"]))
            ps.append(math.log(ea / eb) / math.log(ha / hb) if ea > 0 and eb > 0 else float("nan"))
        out[key] = (rs, ps)
    return out


def table(rows):
    lines = ["| case | mesh | model | faces | max error | RMS error | order | Newton its | time (s) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for (case, kind, model), (rs, ps) in orders(rows).items():
        faces = " / ".join(str(r["faces"]) for r in rs)
        fmt = lambda k: " / ".join(f"{100 * float(r[k]):.2g}%" + ("" if str(r["converged"]) == "True" else "†") for r in rs)
        its = " / ".join(str(r["newton_iterations"]) for r in rs)
        ts = " / ".join(f"{float(r['wall_seconds']):.2g}" for r in rs)
        order = f"{ps[-1]:.2f}" if ps else ""
        lines.append(f"| {case} | {kind} | {model} | {faces} | {fmt('max_error_rel')} | {fmt('rms_error_rel')} | {order} | {its} | {ts} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "scripts", "results", "convergence_study.csv"))
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--table-only", action="store_true")
    a = ap.parse_args()
    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    rows = list(csv.DictReader(open(a.out))) if a.table_only else study(a.out, a.threads, a.quick)
    print()
    print(table(rows))
    print(f"\n(† = the solve did not converge; CSV: {a.out})")


if __name__ == "__main__":
    main()
