#!/usr/bin/env python3
"""What self-contact costs an implicit (dynamic) run with nothing in contact: the draping
cloth (`settings/cloth_drape_baraff_witkin.toml`, 800 faces, pinned at two corners, falling
up to 3 cm per step) for its first second, with `[self_contact]` enabled and disabled,
alternating, on 1 and 2 threads.

    python3 scripts/implicit_contact_cost.py [--shellsim PATH] [--work DIR] [--repeats N]

The cloth never comes near itself: with contact enabled every step pays the broad phase over
the predicted start's paths, the pairs' gathering, and the check of each Newton step (answered
without a broad phase while no vertex moves far from where the last one was cached). Both runs
take the same steps and Newton iterations (checked). Reported per thread count: the median
wall seconds with and without, their ratio, and the contact's own clocks from `log.csv` (broad
phase, CCD). The machine is shared: the runs alternate, so that a slow spell hits both. Only
the standard library is used.
"""

import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run(shellsim, work, contact, threads, k, end):
    """One run; returns (wall s, steps, Newton iterations, broad s, CCD s)."""
    out = os.path.join(work, f"drape_{contact}_{threads}_{k}")
    cmd = [
        shellsim,
        os.path.join(ROOT, "settings", "cloth_drape_baraff_witkin.toml"),
        os.path.join(ROOT, "meshes", "cloth_square.vtk"),
        "--out",
        out,
        "-q",
        "--overwrite",
        "--threads",
        str(threads),
        "--set",
        f"time.end={end}",
        "--set",
        f"self_contact.enabled={'true' if contact else 'false'}",
    ]
    subprocess.run(cmd, capture_output=True, check=True)
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    with open(os.path.join(out, "log.csv")) as f:
        last = list(csv.DictReader(f))[-1]
    clock = [float(last.get(f"self_contact_{p}_seconds", 0.0)) for p in ("broad", "ccd")]
    return (s["wall_seconds"], s["steps"], s["newton_iterations"], *clock)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--shellsim", default=os.path.join(ROOT, "target", "release", "shellsim"))
    ap.add_argument("--work", default=None)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--end", type=float, default=1.0, help="simulated seconds")
    a = ap.parse_args()
    work = a.work or tempfile.mkdtemp(prefix="implicit_contact_cost_")
    rows = []
    for threads in (1, 2):
        runs = {False: [], True: []}
        for k in range(a.repeats):
            for contact in (False, True):
                runs[contact].append(run(a.shellsim, work, contact, threads, k, a.end))
        without, with_ = runs[False], runs[True]
        if {r[1:3] for r in without} != {r[1:3] for r in with_}:
            sys.exit(f"steps or iterations differ: {without} {with_}")
        off = statistics.median(r[0] for r in without)
        on = statistics.median(r[0] for r in with_)
        broad = statistics.median(r[3] for r in with_)
        ccd = statistics.median(r[4] for r in with_)
        rows.append(
            {
                "threads": threads,
                "steps": without[0][1],
                "newton_iterations": without[0][2],
                "seconds_without": off,
                "seconds_with": on,
                "ratio": on / off,
                "broad_seconds": broad,
                "ccd_seconds": ccd,
                "clocks_over_run_without": (broad + ccd) / off,
            }
        )
        print(json.dumps(rows[-1]), flush=True)


if __name__ == "__main__":
    main()
