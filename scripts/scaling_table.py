#!/usr/bin/env python3
"""Where the time of an implicit solve goes as the mesh grows: the curvature-programmed cone of
settings/gcm_cone.toml (flat sector to its cone, statics) on jittered meshes of about 1k, 10k
and 100k faces (--faces for others, 1M included if it fits in memory), one run each.

Per mesh, from summary.json: faces, unknowns, the ordering kept (AMD or nested dissection),
the factor's non-zeros and flops, Newton iterations and factorisations, and the wall time of
the build, the symbolic analysis, the assembly, the factorisation, the solves and the whole run,
in total and per factorisation. Runs on --threads (default 2) and writes
scripts/results/scaling_table.csv; prints a Markdown table.

Uses target/release/shellsim (or $SHELLSIM_BIN); build it first. Standard library only.
"""

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from build_scaling import BIN, ROOT, SETTINGS, cone  # noqa: E402

COLUMNS = ["faces", "unknowns", "ordering", "factor_nonzeros", "factor_flops",
           "newton_iterations", "factorisations", "build_s", "analysis_s", "assembly_s",
           "factorisation_s", "solve_s", "wall_s", "ms_per_factorisation", "peak_rss_mb"]


def run(mesh, out, threads):
    """One run of the cone on `mesh`: its summary and the peak resident memory (MB)."""
    cmd = [BIN, SETTINGS, mesh, "--out", out, "-q", "--overwrite", "--threads", str(threads)]
    t = ["/usr/bin/time", "-f", "%M"] if os.path.exists("/usr/bin/time") else []
    p = subprocess.run(t + cmd, check=True, stderr=subprocess.PIPE, text=True)
    rss = float(p.stderr.strip().splitlines()[-1]) / 1024 if t else math.nan
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f), rss


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--faces", type=int, nargs="*", default=[1000, 10000, 100000])
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in a.faces:
            mesh = os.path.join(tmp, f"cone_{n}.vtk")
            cone(mesh, n)
            s, rss = run(mesh, os.path.join(tmp, f"out_{n}"), a.threads)
            ls, t = s["linear_system"], s["timing"]
            rows.append({
                "faces": s["faces"], "unknowns": ls["unknowns"], "ordering": ls["ordering"],
                "factor_nonzeros": ls["factor_nonzeros"], "factor_flops": ls["factor_flops"],
                "newton_iterations": s["newton_iterations"],
                "factorisations": ls["factorisations"], "build_s": t["build"],
                "analysis_s": t["analysis"], "assembly_s": t["assembly"],
                "factorisation_s": t["factorisation"], "solve_s": t["solve"],
                "wall_s": s["wall_seconds"],
                "ms_per_factorisation": 1e3 * t["factorisation"] / max(ls["factorisations"], 1),
                "peak_rss_mb": rss,
            })
            print(f"{s['faces']} faces done in {s['wall_seconds']:.1f} s", file=sys.stderr)
    os.makedirs(os.path.join(ROOT, "scripts", "results"), exist_ok=True)
    path = os.path.join(ROOT, "scripts", "results", "scaling_table.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)
    print("| " + " | ".join(COLUMNS) + " |")
    print("|" + "---|" * len(COLUMNS))
    for r in rows:
        print("| " + " | ".join(f"{r[c]:.3g}" if isinstance(r[c], float) else str(r[c])
                                for c in COLUMNS) + " |")


if __name__ == "__main__":
    main()
