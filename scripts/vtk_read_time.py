#!/usr/bin/env python3
"""Times VTK's own reader (vtkXMLUnstructuredGridReader, as ParaView uses it) on .vtu files:
the median of 5 reads of each, in ms, with the file's size.

    cargo bench --bench kernels -- frame_write     # writes target/frame_write/*.vtu (~100k faces)
    python3 scripts/vtk_read_time.py target/frame_write/*.vtu

Needs VTK's Python package (.venv/bin/python, which scripts/test.sh makes).
"""
import os
import statistics
import sys
import time

import vtk

for path in sys.argv[1:]:
    times = []
    for _ in range(5):
        r = vtk.vtkXMLUnstructuredGridReader()
        r.SetFileName(path)
        t = time.perf_counter()
        r.Update()
        times.append(time.perf_counter() - t)
        cells = r.GetOutput().GetNumberOfCells()
    print(f"{os.path.basename(path):40s} {os.path.getsize(path) / cells:7.1f} B/face "
          f"{1e3 * statistics.median(times):8.1f} ms  ({cells} cells)")
