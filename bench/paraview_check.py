# Opens a run's output/results.pvd in ParaView (pvbatch), as a user would: time steps, and at the
# first and last frames each block's points and arrays (one block for a particle set; mpm-fem's
# .pvd has two parts, the soil's points and the grid's nodes), and a screenshot of the last frame
# coloured by the x displacement (or, without one, the pressure). For the .pvtu series of
# `mpirun -n N swmpm solve` (issue 28). Debian 12's paraview replaces libvtk9-dev (python3-paraview
# conflicts with python3-vtk9): install it apart from the build, then reinstall libvtk9-dev.
# Usage: xvfb-run -a pvbatch bench/paraview_check.py RUN/output/results.pvd picture.png
from paraview.simple import *
from paraview import servermanager
import sys


def leaves(data, path=()):
    """The datasets of a (possibly nested) multiblock, with their block path."""
    if data is None:
        return []
    if data.IsA("vtkMultiBlockDataSet"):
        return [leaf for b in range(data.GetNumberOfBlocks()) for leaf in leaves(data.GetBlock(b), path + (b,))]
    if data.IsA("vtkMultiPieceDataSet"):
        return [leaf for b in range(data.GetNumberOfPieces()) for leaf in leaves(data.GetPiece(b), path + (b,))]
    return [(path, data)]


r = PVDReader(FileName=sys.argv[1])
r.UpdatePipelineInformation()
times = r.TimestepValues
print("timesteps", len(times), times[:2], "...", times[-1])
colour = None
ranges = {}  # the last frame's range of each array printed, over the blocks
for t in (times[0], times[-1]):
    r.UpdatePipeline(t)
    for path, d in leaves(servermanager.Fetch(r)):
        pd = d.GetPointData()
        names = [pd.GetArrayName(i) for i in range(pd.GetNumberOfArrays())]
        print("t", t, "block", list(path), "points", d.GetNumberOfPoints(), "arrays", names)
        for name, component in (("displacement", 0), ("pressure", 0), ("phase_field", 0)):
            a = pd.GetArray(name)
            if a is not None:
                lo, hi = a.GetRange(component)
                print("   ", name + ("_x" if name == "displacement" else ""), "range", (lo, hi))
                colour = colour or name
                if t == times[-1]:
                    old_lo, old_hi = ranges.get(name, (lo, hi))
                    ranges[name] = (min(lo, old_lo), max(hi, old_hi))
# a picture as a user would see it
r.UpdatePipeline(times[-1])
v = GetActiveViewOrCreate("RenderView")
v.ViewSize = [900, 400]
disp = Show(r, v)
ColorBy(disp, ("POINTS", colour, "X") if colour == "displacement" else ("POINTS", colour))
disp.SetRepresentationType("Points")
disp.PointSize = 4
v.ViewTime = times[-1]
ResetCamera(v)
GetColorTransferFunction(colour).RescaleTransferFunction(*ranges[colour])  # the last frame's range
SaveScreenshot(sys.argv[2], v)
