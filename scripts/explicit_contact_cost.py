#!/usr/bin/env python3
"""What self-contact costs an explicit (MorphoShell) run with nothing near contact: the same
scene with `[self_contact]` enabled and disabled, alternating, on 1 and 2 threads.

    python3 scripts/explicit_contact_cost.py [--shellsim PATH] [--work DIR] [--repeats N]

Scenes (from `settings/`, their own meshes), each run for a fixed number of long times so
that every run takes the same steps:

- `gcm_cone_explicit`: the 793-face programmed cone, 0.01 long times (8,880 steps);
- `bilayer_strip_explicit`: the 320-face bilayer strip, 0.05 long times (17,000 steps).

Neither comes near contact: with it enabled the pairs are gathered once or a few times, and
every step pays the contact term's gradient over no pair, the displacement bounds' pass over
the vertices, and the loss of the fused step (the scene has two terms). Reported per scene and
thread count: the median microseconds per face-step (`explicit.microseconds_per_face_step` in
`summary.json`) with and without, and their ratio. The machine is shared: the runs alternate,
so that a slow spell hits both. Only the standard library is used.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

SCENES = [
    ("gcm_cone_explicit", "gcm_cone_793.vtk", 0.01),
    ("bilayer_strip_explicit", "bilayer_strip.vtk", 0.05),
]


def run(shellsim, work, scene, mesh, long_times, contact, threads, k):
    """One run; returns its µs per face-step and the contact's gatherings (None without)."""
    out = os.path.join(work, f"{scene}_{contact}_{threads}_{k}")
    cmd = [
        shellsim,
        os.path.join(ROOT, "settings", scene + ".toml"),
        os.path.join(ROOT, "meshes", mesh),
        "--out",
        out,
        "-q",
        "--overwrite",
        "--threads",
        str(threads),
        "--set",
        f"explicit.max_long_times={long_times}",
        "--set",
        f"self_contact.enabled={'true' if contact else 'false'}",
    ]
    subprocess.run(cmd, capture_output=True, check=False)
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    e = s["explicit"]
    return e["microseconds_per_face_step"], e.get("contact_gathers")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--shellsim", default=os.path.join(ROOT, "target/release/shellsim"))
    ap.add_argument("--work", default=None)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    work = a.work or tempfile.mkdtemp(prefix="explicit_contact_")
    print(f"{'scene':24} {'threads':>7} {'without µs':>11} {'with µs':>9} {'ratio':>6} gathers")
    for scene, mesh, lt in SCENES:
        for threads in (1, 2):
            off, on, gathers = [], [], None
            for k in range(a.repeats):
                off.append(run(a.shellsim, work, scene, mesh, lt, False, threads, k)[0])
                t, gathers = run(a.shellsim, work, scene, mesh, lt, True, threads, k)
                on.append(t)
            m_off, m_on = statistics.median(off), statistics.median(on)
            print(
                f"{scene:24} {threads:>7} {m_off:>11.4f} {m_on:>9.4f} {m_on / m_off:>6.2f} {gathers}",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
