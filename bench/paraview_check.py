# Opens a run's output/results.pvd in ParaView (pvbatch), as a user would: time steps, points and
# arrays of the first and last frames, and a screenshot of the last. For the .pvtu series of
# `mpirun -n N swmpm solve` (issue 28). Debian 12's paraview replaces libvtk9-dev (python3-paraview
# conflicts with python3-vtk9): install it apart from the build, then reinstall libvtk9-dev.
# Usage: xvfb-run -a pvbatch bench/paraview_check.py RUN/output/results.pvd picture.png
from paraview.simple import *
import sys
r = PVDReader(FileName=sys.argv[1])
r.UpdatePipelineInformation()
times = r.TimestepValues
print("timesteps", len(times), times[:2], "...", times[-1])
for t in (times[0], times[-1]):
    r.UpdatePipeline(t)
    info = r.GetDataInformation()
    print("t", t, "points", info.GetNumberOfPoints(), "cells", info.GetNumberOfCells())
    pd = r.PointData
    print("arrays", [pd.GetArray(i).GetName() for i in range(pd.GetNumberOfArrays())])
    d = pd["displacement"].GetRange(0)
    print("displacement_x range", d)
# a picture as a user would see it
r.UpdatePipeline(times[-1])
v = GetActiveViewOrCreate("RenderView")
v.ViewSize = [900, 400]
disp = Show(r, v)
ColorBy(disp, ("POINTS", "displacement", "X"))
disp.SetRepresentationType("Points")
disp.PointSize = 4
v.ViewTime = times[-1]
ResetCamera(v)
disp.RescaleTransferFunctionToDataRange(True)
SaveScreenshot(sys.argv[2], v)
