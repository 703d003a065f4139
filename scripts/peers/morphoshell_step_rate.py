"""MorphoShell's explicit step time, in microseconds per triangle-step, for comparison with
shellsim's `cargo bench --bench kernels -- explicit_step_793` (the same GCM cone mesh).

Converts a shellsim mesh carrying `abar_info`/`bbar_info` (for example meshes/gcm_cone_793.vtk)
into MorphoShell's ASCII POLYDATA input (uniform thickness and shear modulus from the
settings), runs a MorphoShell executable on it with OMP_NUM_THREADS threads for SECONDS, and
times the steps between its output lines, separately while it dials and while it waits for
equilibrium (the first output, after its setup, is skipped).

    python scripts/peers/morphoshell_step_rate.py MORPHOSHELL_EXE SETTINGS MESH THREADS SECONDS

SETTINGS is a MorphoShell settings file; use `dialling_from_ansatz_rather_than_ref_state =
false` and an `outputs_per_char_long_time` of about 40, so that output lines come every few
seconds and writing frames costs nothing measurable. Needs the `vtk` module (the project's
virtual environment has it).
"""
import os
import re
import subprocess
import sys
import tempfile
import time

import vtk
from vtk.util.numpy_support import vtk_to_numpy


def field(grid, name):
    for data in (grid.GetCellData(), grid.GetFieldData()):
        for i in range(data.GetNumberOfArrays()):
            if data.GetArrayName(i) == name:
                return vtk_to_numpy(data.GetArray(i))
    sys.exit(f"{name}: no such face field in the mesh")


def write_morphoshell_mesh(src, dst):
    reader = vtk.vtkUnstructuredGridReader()
    reader.SetFileName(src)
    reader.ReadAllFieldsOn()
    reader.Update()
    grid = reader.GetOutput()
    points = vtk_to_numpy(grid.GetPoints().GetData())
    nf = grid.GetNumberOfCells()
    abar, bbar = field(grid, "abar_info"), field(grid, "bbar_info")
    with open(dst, "w") as f:
        f.write(f"# vtk DataFile Version 2.0\nmesh\nASCII\nDATASET POLYDATA\nPOINTS {len(points)} double\n")
        for p in points:
            f.write("%.15e %.15e %.15e\n" % tuple(p))
        f.write(f"POLYGONS {nf} {4 * nf}\n")
        for c in range(nf):
            ids = grid.GetCell(c).GetPointIds()
            f.write(f"3 {ids.GetId(0)} {ids.GetId(1)} {ids.GetId(2)}\n")
        f.write(f"CELL_DATA {nf}\nFIELD tri_quantities 5\nabar_info 3 {nf} double\n")
        for a in abar:
            f.write("%.15e %.15e %.15e\n" % tuple(a))
        f.write(f"bbar_info 3 {nf} double\n")
        for b in bbar:
            f.write("%.15e %.15e %.15e\n" % tuple(b))
        for name in ("ref_thicknesses", "ref_shear_moduli"):
            f.write(f"{name} 1 {nf} double\n" + "-1234\n" * nf)
        f.write(f"tri_tags 1 {nf} int\n" + "0\n" * nf)
        n = len(points)
        f.write(f"POINT_DATA {n}\nFIELD node_quantities 2\nconstraint_indicators 1 {n} int\n")
        f.write("0\n" * n + f"node_tags 1 {n} int\n" + "0\n" * n)
    return nf


def main():
    if len(sys.argv) != 6:
        sys.exit(__doc__)
    exe, settings, mesh, threads, seconds = sys.argv[1:]
    work = tempfile.mkdtemp(prefix="morphoshell_rate_")
    nf = write_morphoshell_mesh(mesh, os.path.join(work, "mesh.vtk"))
    with open(settings) as s, open(os.path.join(work, "settings.txt"), "w") as d:
        d.write(s.read())
    env = dict(os.environ, OMP_NUM_THREADS=threads)
    proc = subprocess.Popen([os.path.abspath(exe), "settings.txt", "mesh.vtk"], cwd=work,
                            stdout=subprocess.PIPE, text=True, env=env)
    marks, start = [], time.monotonic()
    for line in proc.stdout:
        m = re.search(r"stepcount = (\d+).*dial factor = ([-0-9.e+]+)", line)
        if m:
            marks.append((time.monotonic(), int(m.group(1)), float(m.group(2))))
        if time.monotonic() - start > float(seconds):
            break
    proc.kill()
    proc.wait()
    marks = marks[1:]
    for name, seg in (("dialling", [m for m in marks if m[2] < 0.999]),
                      ("waiting", [m for m in marks if m[2] >= 0.999])):
        if len(seg) < 2:
            print(f"{name}: fewer than two output lines in {seconds} s")
            continue
        (ta, sa, _), (tb, sb, _) = seg[0], seg[-1]
        us = 1e6 * (tb - ta) / ((sb - sa) * nf)
        print(f"{nf} faces, {threads} thread(s), {name}: {sb - sa} steps in {tb - ta:.2f} s, "
              f"{us:.3f} us per triangle-step")


if __name__ == "__main__":
    main()
