"""pvpython check of the sluice reader plugin: loads it, opens the converted
sample through ParaView's reader factory, checks counts, times and every
particle's coordinates of a frame against `sluice export`, lowers the LOD
level, and saves a screenshot that must not be blank.

    xvfb-run -a pvpython --force-offscreen-rendering check_plugin.py \
        PLUGIN FILE.sluice FRAME3.csv SERIES.pvd SHOT.png

FRAME3.csv is `sluice export FILE --frames 3`, SERIES.pvd the collection
`sluice export FILE -o series/f.vtp` writes (its timesteps are the times).
"""
import csv
import sys
from xml.etree import ElementTree

from paraview import servermanager
from paraview.simple import (GetActiveViewOrCreate, LoadPlugin, OpenDataFile, Render, ResetCamera,
                             SaveScreenshot, Show)
import numpy as np
from vtkmodules.vtkIOImage import vtkPNGReader
from vtkmodules.util.numpy_support import vtk_to_numpy

plugin, path, csv_path, pvd_path, shot = sys.argv[1:6]
failures = []


def check(ok, what):
    print(("ok      " if ok else "FAILED  ") + what)
    if not ok:
        failures.append(what)


LoadPlugin(plugin, ns=globals())
reader = OpenDataFile(path)  # by extension: the plugin's ReaderFactory hint
check(reader is not None and reader.GetXMLName() == "SluiceReader", "OpenDataFile picks the sluice reader")
reader.UpdatePipelineInformation()
times = list(reader.TimestepValues)
expected_times = [float(d.get("timestep")) for d in ElementTree.parse(pvd_path).iter("DataSet")]
check(len(times) == 13, f"13 time steps ({len(times)})")
check(len(expected_times) == 13 and all(abs(a - b) <= 1e-6 * max(1.0, abs(b)) for a, b in zip(times, expected_times)),
      "times are the file's (as export's .pvd states them)")

with open(csv_path, newline="") as f:
    rows = list(csv.reader(f))
header, body = rows[0], rows[1:]
reader.UpdatePipeline(times[3])
data = servermanager.Fetch(reader)
n = data.GetNumberOfPoints()
check(n == len(body), f"frame 3 has export's {len(body)} particles ({n})")
check(data.GetNumberOfVerts() == n, "one vertex cell per particle")
points = vtk_to_numpy(data.GetPoints().GetData())
x, y, z, rho = (header.index(c) for c in ("x", "y", "z", "rho"))
# The CSV holds each float32 in its shortest exact form: equal as float32.
expected = np.array([[row[x], row[y], row[z]] for row in body], dtype=np.float64).astype(np.float32)
mismatch = int((points != expected).any(axis=1).sum()) if points.shape == expected.shape else len(body)
check(mismatch == 0, f"every particle's coordinates equal export's ({mismatch} differ)")
pd = data.GetPointData()
check(pd.GetArray("lod") is not None and pd.GetArray("rho") is not None, "lod and rho are point arrays")
check(np.float32(pd.GetArray("rho").GetValue(0)) == np.float32(float(body[0][rho])), "rho of particle 0 equals export's")
check(data.GetFieldData().GetArray("TimeValue").GetValue(0) == times[3], "TimeValue is the frame's time")

reader.LODLevel = 0.25
reader.UpdatePipeline(times[3])
thin = servermanager.Fetch(reader).GetNumberOfPoints()
check(0.15 * n < thin < 0.35 * n, f"LOD level 0.25 keeps about a quarter ({thin} of {n})")
reader.Attributes = ["p"]
reader.UpdatePipeline(times[12])
last = servermanager.Fetch(reader)
check(last.GetPointData().GetArray("rho") is None and last.GetPointData().GetArray("p") is not None,
      "the attribute selection is honoured")

view = GetActiveViewOrCreate("RenderView")
display = Show(reader, view)
display.SetRepresentationType("Points")
display.PointSize = 3
ResetCamera(view)
Render(view)
SaveScreenshot(shot, view, ImageResolution=[640, 360])
png = vtkPNGReader()
png.SetFileName(shot)
png.Update()
image = vtk_to_numpy(png.GetOutput().GetPointData().GetScalars()).astype(int)
background = image[0]
changed = int((abs(image[:, :3] - background[:3]).max(axis=1) > 30).sum())
check(changed > 2000, f"the screenshot shows the particles ({changed} pixels differ from the background)")

print(f"{len(failures)} failure(s)")
# Failures raise (pvpython then exits non-zero); success ends the script
# normally: sys.exit(0) here tears the render window down out of order
# (GLXBadContext at exit, exit status 1) where a normal end does not.
if failures:
    raise RuntimeError("; ".join(failures))
