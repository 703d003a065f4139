"""Runs every example scene in settings/ at full size and draws one frame of each with
`shellsim render` into docs/images/scenes/<scene>.png (the README's gallery).

    python3 scripts/readme_pictures.py [SCENE...] [--size 640x480] [--work /tmp/shellsim_pictures]
                                       [--no-run]

Each scene names the time (dynamic runs), dial (static runs with continuation frames) or
"final" frame to draw, the field, the view and, where the field has singular points, a colour
range. Prints each scene's wall time and the frame drawn. Needs `cargo build --release` first.
"""

import argparse
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
BIN = os.path.join(ROOT, "target", "release", "shellsim")

# scene: (frame: "final" or a time/dial, field, view, range or None)
SCENES = {
    "static_from_mesh": ("final", "mean_curvature", "30,40", None),
    "dynamic_cylinder": ("final", "mean_curvature", "30,20", None),
    "gcm_cone": ("final", "mean_curvature", "30,30", None),
    "gcm_cone_explicit": ("final", "mean_curvature", "30,30", None),
    "lce_cone": ("final", "mean_curvature", "30,25", "0,3"),
    "cone_squeezed": ("final", "max_stretch", "30,35", None),
    "bilayer_strip_explicit": ("final", "mean_curvature", "20,25", None),
    "cloth_drape_baraff_witkin": ("final", "max_stretch", "-70,10", "1,1.25"),
    "cloth_drape_koiter": ("final", "max_stretch", "-70,10", "1,1.25"),
    "cloth_over_sphere_and_box": ("final", "mean_curvature", "-60,30", None),
    "cloth_folds_on_sphere": ("final", "mean_curvature", "-60,30", None),
    "balloon_sphere": ("final", "max_stretch", "iso", None),
    "balloon_teddy": ("final", "max_stretch", "front", None),
    "balloon_thickness": ("final", "max_stretch", "front", None),
    "paper_strip_md": (1.3, "mean_curvature", "30,25", None),
    "paper_strip_cd": (1.3, "mean_curvature", "30,25", None),
    "paper_annulus": (0.8, "mean_curvature", "30,45", None),
    "paper_strip_rolls_onto_itself": (1.3, "mean_curvature", "65,15", None),
    "paper_annulus_rolls_up": (1.2, "mean_curvature", "30,25", None),
    "gel_disk_hyperbolic": ("final", "gauss_curvature", "30,30", "-2000,0"),
    "conformal_cap": ("final", "mean_curvature", "30,20", None),
    "paper_walker": (0.4, "moisture_bottom", "-60,15", None),
    "spoon_heated": ("final", "temperature_max_top", "-50,35", None),
    "leaf_drying": ("final", "mean_curvature", "20,25", "-60,60"),
    "gelatin_tube": ("final", "mean_curvature", "30,25", None),
    "caterpillar": (0.25, "moisture_top", "-60,25", None),
}


def scene_mesh(scene):
    with open(os.path.join(ROOT, "settings", scene + ".toml")) as f:
        for line in f:
            m = re.match(r"#\s*mesh:\s*(\S+)", line)
            if m:
                return os.path.join(ROOT, m.group(1))
    sys.exit(f"settings/{scene}.toml has no '# mesh:' line")


def frames(out):
    """(timestep, file) of every frame in the run's series.pvd, in order."""
    with open(os.path.join(out, "series.pvd")) as f:
        text = f.read()
    return [(float(t), os.path.join(out, p))
            for t, p in re.findall(r'timestep="([^"]+)"[^>]*file="([^"]+)"', text)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scenes", nargs="*", default=list(SCENES))
    ap.add_argument("--size", default="640x480")
    ap.add_argument("--work", default="/tmp/shellsim_pictures")
    ap.add_argument("--no-run", action="store_true",
                    help="draw from the runs already in --work")
    args = ap.parse_args()
    os.makedirs(os.path.join(ROOT, "docs", "images", "scenes"), exist_ok=True)
    for scene in args.scenes:
        when, field, view, rng = SCENES[scene]
        out = os.path.join(args.work, scene)
        t = time.time()
        code = 0
        if not args.no_run:
            code = subprocess.run([BIN, os.path.join(ROOT, "settings", scene + ".toml"),
                                   scene_mesh(scene), "--out", out, "--overwrite", "-q"]).returncode
        wall = time.time() - t
        if code not in (0, 1):
            sys.exit(f"{scene}: exit {code}")
        series = frames(out)
        if when == "final":
            stamp, frame = series[-1]
        else:
            stamp, frame = min(series, key=lambda s: abs(s[0] - when))
        png = os.path.join(ROOT, "docs", "images", "scenes", scene + ".png")
        cmd = [BIN, "render", frame, "-o", png, "--field", field, f"--view={view}",
               "--size", args.size]
        if rng:
            cmd += ["--range", rng]
        subprocess.run(cmd, check=True)
        print(f"{scene}: exit {code}, {wall:.1f} s, frame {os.path.basename(frame)} "
              f"at {stamp:g}, {field}", flush=True)


if __name__ == "__main__":
    main()
