"""Renders the last step of a Tessera snapshot series with ParaView: each body a sphere glyph of
its radius (particles.xmf) or each grain's own surface (grains.xmf, shaped bodies), coloured by
speed, seen along +y (parallel projection).

usage: xvfb-run -a pvbatch tools/paraview_snapshot.py RUN_DIR/snapshots/particles.xmf OUT.png
       xvfb-run -a pvbatch tools/paraview_snapshot.py RUN_DIR/snapshots/grains.xmf OUT.png
(Debian packages paraview, python3-paraview and xvfb; not needed by the build or the tests.)
"""
import sys
from paraview.simple import *
xmf = sys.argv[1]
out = sys.argv[2]
reader = XDMFReader(FileNames=[xmf])
reader.UpdatePipelineInformation()
times = reader.TimestepValues
print("time steps:", len(times) if hasattr(times, "__len__") else times)
reader.UpdatePipeline(times[-1] if hasattr(times, "__len__") else 0.0)
info = reader.GetDataInformation()
print("points:", info.GetNumberOfPoints())
pd = reader.PointData
print("arrays:", [pd.GetArray(i).GetName() for i in range(pd.GetNumberOfArrays())])
if xmf.endswith("grains.xmf"):
    glyph = reader  # surfaces as they are
else:
    glyph = Glyph(Input=reader, GlyphType="Sphere")
    glyph.ScaleArray = ["POINTS", "radius"]
    glyph.ScaleFactor = 2.0
    glyph.GlyphMode = "All Points"
view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [900, 700]
d = Show(glyph, view)
ColorBy(d, ("POINTS", "velocity", "Magnitude"))
d.RescaleTransferFunctionToDataRange(True)
view.ViewTime = times[-1]
b = reader.GetDataInformation().GetBounds()
centre = [(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2]
view.CameraParallelProjection = 1
view.CameraParallelScale = 0.6 * max(b[1] - b[0], b[5] - b[4])
view.CameraPosition = [centre[0], b[2] - 3 * (b[3] - b[2] + b[5] - b[4]), centre[2]]
view.CameraFocalPoint = centre
view.CameraViewUp = [0, 0, 1]
view.Update()
SaveScreenshot(out, view, ImageResolution=[900, 700])
print("saved", out)
