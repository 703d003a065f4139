#!/usr/bin/env python3
"""Runs two shellsim binaries on every scene in settings/ and compares their frames.

    python3 scripts/compare_binaries.py OLD_BINARY NEW_BINARY [--end-cap SECONDS] [--out DIR]

Each scene runs with legacy ASCII frames (`--set output.format="vtk_ascii"`); long dynamic scenes
can be shortened with --end-cap (the same cap for both binaries). For every frame both wrote, the
largest vertex position difference is reported relative to the final frame's bounding-box
diagonal, with the wall times of both runs.
"""
import argparse, json, math, os, pathlib, subprocess, sys, time

ROOT = pathlib.Path(__file__).resolve().parent.parent


def points(path):
    lines = path.read_text().split("\n")
    for i, line in enumerate(lines):
        if line.startswith("POINTS"):
            n = int(line.split()[1])
            vals = []
            j = i + 1
            while len(vals) < 3 * n:
                vals.extend(float(v) for v in lines[j].split())
                j += 1
            return [vals[3 * k:3 * k + 3] for k in range(n)]
    raise ValueError(f"{path}: no POINTS")


def run(binary, settings, mesh, out, extra):
    t0 = time.time()
    cmd = [binary, str(settings), str(mesh), "--out", str(out), "--set", 'output.format="vtk_ascii"'] + extra
    r = subprocess.run(cmd, capture_output=True, text=True)
    return r.returncode, time.time() - t0, r.stderr


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--end-cap", type=float, default=None)
    ap.add_argument("--out", default="/tmp/shellsim-compare")
    args = ap.parse_args()
    rows = []
    for settings in sorted((ROOT / "settings").glob("*.toml")):
        first = settings.read_text().split("\n")[0]
        if not first.startswith("# mesh:"):
            continue
        mesh = ROOT / first.split(":", 1)[1].strip()
        extra = []
        text = settings.read_text()
        if args.end_cap is not None and 'mode = "dynamic"' in text:
            extra = ["--set", f"time.end={args.end_cap}"]
        res = {}
        for tag, binary in [("old", args.old), ("new", args.new)]:
            out = pathlib.Path(args.out) / settings.stem / tag
            subprocess.run(["rm", "-rf", str(out)])
            res[tag] = (out,) + run(binary, settings, mesh, out, extra)
        frames_old = sorted(res["old"][0].glob("frame_*.vtk"))
        frames_new = sorted(res["new"][0].glob("frame_*.vtk"))
        worst = 0.0
        final = 0.0
        diag = 1.0
        if frames_old and frames_new:
            last = points(frames_new[-1])
            lo = [min(p[c] for p in last) for c in range(3)]
            hi = [max(p[c] for p in last) for c in range(3)]
            diag = math.dist(lo, hi) or 1.0
            for fo, fn in zip(frames_old, frames_new):
                po, pn = points(fo), points(fn)
                d = max(math.dist(a, b) for a, b in zip(po, pn)) / diag
                worst = max(worst, d)
                final = d
        rows.append({
            "scene": settings.stem,
            "exit_old": res["old"][1], "exit_new": res["new"][1],
            "frames_old": len(frames_old), "frames_new": len(frames_new),
            "max_rel_diff": worst, "final_rel_diff": final,
            "seconds_old": round(res["old"][2], 2), "seconds_new": round(res["new"][2], 2),
        })
        print(json.dumps(rows[-1]), flush=True)


if __name__ == "__main__":
    main()
