"""A .sluice file in ParaView from pvpython: the sluice reader plugin, a
lowered LOD level, colour by an attribute, particles as point Gaussians.

    pvpython --force-offscreen-rendering screenshot.py PLUGIN.so FILE.sluice OUT.png \
        [--frame N] [--lod 0.3] [--color rho] [--radius R]
"""
import argparse

from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetAnimationScene, LoadPlugin, OpenDataFile, Render,
                             SaveScreenshot, Show)

p = argparse.ArgumentParser()
p.add_argument("plugin")
p.add_argument("file")
p.add_argument("out")
p.add_argument("--frame", type=int, default=-1, help="frame number (negative: from the end)")
p.add_argument("--lod", type=float, default=0.3, help="LOD level: the fraction of the particles loaded")
p.add_argument("--color", default="rho")
p.add_argument("--radius", type=float, default=0, help="splat radius, world units (0: the data's size / 150)")
a = p.parse_args()

LoadPlugin(a.plugin, ns=globals())
reader = OpenDataFile(a.file)  # the plugin's reader, by the .sluice extension
reader.LODLevel = a.lod
reader.UpdatePipelineInformation()
times = reader.TimestepValues
scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
scene.AnimationTime = times[a.frame]

view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [960, 540]
view.OrientationAxesVisibility = 0
display = Show(reader, view)
display.SetRepresentationType("Point Gaussian")
b = reader.GetDataInformation().GetBounds()  # xmin, xmax, ymin, ymax, zmin, zmax
size = max(b[1] - b[0], b[3] - b[2], b[5] - b[4])
display.GaussianRadius = a.radius if a.radius > 0 else size / 150
ColorBy(display, ("POINTS", a.color))
display.RescaleTransferFunctionToDataRange(True, False)
display.SetScalarBarVisibility(view, True)
# From the front, above, with z up (the sample's up axis).
centre = [(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2]
view.CameraFocalPoint = centre
view.CameraPosition = [centre[0] + 0.6 * size, centre[1] - 1.6 * size, centre[2] + 1.0 * size]
view.CameraViewUp = [0, 0, 1]
view.ResetCamera(False)
Render(view)
SaveScreenshot(a.out, view, ImageResolution=[960, 540])
print(f"wrote {a.out}: frame {a.frame} at t={times[a.frame]:.4g} s, LOD level {a.lod}")
