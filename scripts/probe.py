#!/usr/bin/env python3
"""A hostile user's probe of the whole binary: RUNS runs of `shellsim SETTINGS MESH` on mutated
meshes (truncations, byte flips, extreme numbers, count edits) and mutated settings (extreme
values, removed lines), each in its own folder, with a timeout. It counts exit codes and checks
what each run left behind:

* a panic (stderr says "panicked", or an exit code other than 0, 1, 2), a hang (timeout), or
* exit 2 with any output written, or
* exit 0/1 without summary.json, or NaN/inf/null in log.csv or summary.json, or
* (with `pip install vtk`) a frame holding a non-finite value.

    python3 scripts/probe.py [RUNS] [SEED]        # after cargo build --release (or SHELLSIM_BIN=path)

Prints the counts; exits 1 if any run failed a check.
"""
import json, math, os, random, re, subprocess, sys, tempfile, time

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
BIN = os.environ.get("SHELLSIM_BIN") or os.path.join(ROOT, "target", "release", "shellsim")
EXTREMES = ["0", "-1", "-7", "4294967295", "1e308", "-1e308", "1e-320", "nan", "inf", "9.2e18", "1e160", "3"]
NUM = re.compile(rb"(?<![A-Za-z0-9_])-?\d+(\.\d+)?([eE][-+]?\d+)?")
try:
    import vtk  # noqa: F401
    from vtk.util.numpy_support import vtk_to_numpy
    import numpy as np
except ImportError:
    vtk = None


def mutate(b, rng):
    for _ in range(rng.randint(1, 3)):
        k = rng.randrange(5)
        if k == 0 and b:
            b = b[: rng.randrange(len(b))]
        elif k == 1 and b:
            b = bytearray(b)
            for _ in range(rng.randint(1, 4)):
                i = rng.randrange(len(b))
                b[i] ^= 1 << rng.randrange(8)
            b = bytes(b)
        else:
            nums = list(NUM.finditer(b))
            if nums:
                m = rng.choice(nums)
                if k != 4:
                    new = rng.choice(EXTREMES).encode()
                else:
                    v = float(m.group()) * rng.choice([0, 2, 1000]) + rng.choice([-1, 0, 1])
                    new = (str(int(v)) if abs(v) < 1e15 else repr(v)).encode()
                b = b[: m.start()] + new + b[m.end():]
    return b


def finite_frames(out):
    if vtk is None:
        return True
    for f in os.listdir(out):
        if not f.endswith(".vtu"):
            continue
        r = vtk.vtkXMLUnstructuredGridReader()
        r.SetFileName(os.path.join(out, f))
        r.Update()
        g = r.GetOutput()
        arrays = [g.GetPoints().GetData()] if g.GetPoints() else []
        for data in (g.GetPointData(), g.GetCellData()):
            arrays += [data.GetArray(i) for i in range(data.GetNumberOfArrays())]
        if any(not np.all(np.isfinite(vtk_to_numpy(a))) for a in arrays if a is not None):
            return False
    return True


def main():
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 1000
    rng = random.Random(int(sys.argv[2]) if len(sys.argv) > 2 else 1)
    work = tempfile.mkdtemp(prefix="shellsim-probe-")
    meshes = []
    for prog in ["cylinder", "spherical_cap", "hyperboloid"]:
        p = os.path.join(work, f"{prog}.vtk")
        subprocess.run([BIN, "mesh", "square", "--edge", "0.25", "--program", prog, "-o", p], check=True, capture_output=True)
        meshes.append((p, open(p, "rb").read()))
    # A square with a column of needles 1e-8 wide (the hard case for per-face frames).
    xs, ys = [0, 0.25, 0.5, 0.5 + 1e-8, 0.75, 1.0], [0, 0.25, 0.5, 0.75, 1.0]
    pts = "".join(f"{x!r} {y!r} 0\n" for y in ys for x in xs)
    tris = []
    for j in range(len(ys) - 1):
        for i in range(len(xs) - 1):
            a = j * len(xs) + i
            tris += [(a, a + 1, a + len(xs) + 1), (a, a + len(xs) + 1, a + len(xs))]
    sliver = (f"# vtk DataFile Version 3.0\nsliver\nASCII\nDATASET POLYDATA\nPOINTS {len(xs) * len(ys)} double\n{pts}"
              f"POLYGONS {len(tris)} {4 * len(tris)}\n" + "".join("3 %d %d %d\n" % t for t in tris)).encode()
    meshes.append((os.path.join(work, "sliver.vtk"), sliver))
    settings = [
        b"[material]\nthickness = 0.05\n[rest]\ntarget = \"mesh\"\n",
        b"[material]\nthickness = 0.05\nbending = \"midedge_sin\"\n[rest]\ntarget = \"mesh\"\n",
        b"[material]\nthickness = 0.05\n[rest]\ntarget = \"mesh\"\n[solver]\nmode = \"dynamic\"\n[time]\nend = 0.05\ndt = 0.01\noutput_interval = 0.01\n",
        b"[material]\nthickness = 0.01\n[growth]\nlaw = \"linear_swelling\"\nmu = 0.05\n[moisture]\nenabled = true\n[[moisture.boundary]]\nside = \"top\"\nkind = \"value\"\nvalue = 1.0\n[solver]\nmode = \"dynamic\"\n[time]\nend = 0.05\noutput_interval = 0.025\n",
        b"[material]\nthickness = 0.01\n[growth]\nlaw = \"machine_direction\"\nmu = 0.02\nmu_perp = 0.06\n[moisture]\nenabled = true\nlayers = 5\ngrading = 1.5\ntolerance = 1e-3\ndiffusivity_through = 1e-6\n[[moisture.boundary]]\nside = \"top\"\nkind = \"robin\"\nk = 5e-5\nambient = 0.3\n[[moisture.boundary]]\nside = \"bottom\"\nkind = \"flux\"\nvalue = -1e-7\n[solver]\nmode = \"dynamic\"\n[time]\nend = 0.2\ndt = 0.01\noutput_interval = 0.1\n",
        b"[material]\nthickness = 0.05\n[rest]\ntarget = \"uniform\"\nabar = [16.0, 0.0, 16.0]\nbbar = [0.0, 0.0, 0.0]\n",
        b"[material]\nthickness = 0.01\n[loads]\ngravity = [0.0, 0.0, -9.81]\n[constraints]\nfix_boxes = [{ min = [-1.0, -1.0, -1.0], max = [-0.49, 1.0, 1.0] }]\n[solver]\nmode = \"dynamic\"\n[time]\nend = 1e4\ndt = 1e3\ndt_max = 1e4\noutput_interval = 5e3\n",
    ]
    counts, failures = {}, []
    for i in range(runs):
        d = os.path.join(work, f"r{i}")
        os.makedirs(d)
        path, mesh = rng.choice(meshes)
        s = rng.choice(settings)
        if rng.random() < 0.6:
            mesh = mutate(mesh, rng)
        else:
            s = mutate(s, rng)
        open(os.path.join(d, "m.vtk"), "wb").write(mesh)
        open(os.path.join(d, "s.toml"), "wb").write(s)
        try:
            p = subprocess.run([BIN, "s.toml", "m.vtk", "--out", "o", "-q"], cwd=d, capture_output=True, timeout=60)
            code = p.returncode
            err = p.stderr.decode(errors="replace")
        except subprocess.TimeoutExpired:
            # A run still writing frames when the time is up is slow (a long scene), not hung.
            out = os.path.join(d, "o")
            latest = max((os.path.getmtime(os.path.join(out, f)) for f in os.listdir(out)), default=0) if os.path.isdir(out) else 0
            code, err = ("slow" if time.time() - latest < 10 else "hang"), ""
        counts[code] = counts.get(code, 0) + 1
        out = os.path.join(d, "o")
        written = os.path.isdir(out) and [f for f in os.listdir(out) if not f.startswith(".")]
        bad = None
        if code == "hang":
            bad = "hang"
        elif code == "slow":
            pass
        elif "panicked" in err or code not in (0, 1, 2):
            bad = f"panic or crash (exit {code})"
        elif code == 2 and written:
            bad = f"exit 2 but wrote {written}"
        elif code in (0, 1):
            if not os.path.exists(os.path.join(out, "summary.json")):
                bad = "no summary.json"
            else:
                text = open(os.path.join(out, "summary.json")).read()
                frames = [f for f in os.listdir(out) if f.startswith("frame_")]
                if frames or os.path.exists(os.path.join(out, "log.csv")):
                    text += open(os.path.join(out, "log.csv")).read()
                if re.search(r"\b(nan|NaN|inf|null)\b", text):
                    bad = "non-finite value in summary.json or log.csv"
                elif not finite_frames(out):
                    bad = "non-finite value in a frame"
        if bad:
            failures.append((i, bad, err.strip()[:200]))
    print(f"{runs} runs in {work}: exit codes {dict(sorted(counts.items(), key=str))}")
    print(f"frames checked for non-finite values: {'yes' if vtk else 'no (pip install vtk)'}")
    print(f"failed checks: {len(failures)}")
    for f in failures[:20]:
        print("  run", *f)
    sys.exit(1 if failures else 0)


main()
