"""Renders a flow run's fields in ParaView: the liquid (liquid_fraction = 0.5 contour) of the last
snapshot, coloured by speed, on a slice of the liquid fraction; prints what ParaView read.

usage: xvfb-run -a pvbatch tools/paraview_flow.py RUN_DIR/fields/fields.xmf OUT.png
(Debian packages paraview, python3-paraview and xvfb; not needed by the build or the tests.)
"""
import sys
from paraview.simple import *
xmf, out = sys.argv[1], sys.argv[2]
reader = XDMFReader(FileNames=[xmf])
reader.UpdatePipelineInformation()
times = reader.TimestepValues
times = list(times) if hasattr(times, "__len__") else [times]
print("time steps:", len(times))
reader.UpdatePipeline(times[-1])
info = reader.GetDataInformation()
print("cells:", info.GetNumberOfCells())
cd = reader.CellData
print("cell arrays:", [(cd.GetArray(i).GetName(), cd.GetArray(i).GetNumberOfComponents(), cd.GetArray(i).GetRange(-1))
                       for i in range(cd.GetNumberOfArrays())])
points = CellDatatoPointData(Input=reader)
contour = Contour(Input=points, ContourBy=["POINTS", "liquid_fraction"], Isosurfaces=[0.5])
calc = Calculator(Input=contour, ResultArrayName="speed", Function="mag(velocity)")
view = GetActiveViewOrCreate("RenderView")
scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
scene.AnimationTime = times[-1]
view.ViewTime = times[-1]
view.ViewSize = [900, 700]
view.Background = [1, 1, 1]
d = Show(calc, view)
ColorBy(d, ("POINTS", "speed"))
d.RescaleTransferFunctionToDataRange(True)
d.SetScalarBarVisibility(view, True)
sl = Slice(Input=reader)
sl.SliceType.Normal = [0, 1, 0]
s = Show(sl, view)
ColorBy(s, ("CELLS", "liquid_fraction"))
s.Opacity = 0.35
view.CameraPosition = [0.035, -0.07, 0.06]
view.CameraFocalPoint = [0, 0, 0.012]
view.CameraViewUp = [0, 0, 1]
view.ResetCamera()
view.CameraPosition = [0.035, -0.07, 0.06]
view.CameraFocalPoint = [0, 0, 0.012]
Render(view)
SaveScreenshot(out, view)
print("wrote", out)
