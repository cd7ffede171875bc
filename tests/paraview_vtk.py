"""Opens grainflow's VTK time series (every `.pvd` of a run folder) in
ParaView's own reader and checks that what ParaView reads is what
postprocess/read_output.py reads from the same files: the times and every
cell or point array (values, components, order). The files hold raw
appended data; this is the check that ParaView takes them.

usage: pvpython tests/paraview_vtk.py DIR    (exits 1 on a mismatch)

CI runs it on the sample of `solvers/io/examples/hdf5_sample.rs`, whose
VTK half is read back by read_output.py against its HDF5 half.
"""
import os
import sys

import numpy as np
from paraview.simple import Delete, PVDReader
from vtkmodules.numpy_interface import dataset_adapter as dsa

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "postprocess"))
from read_output import field_frames, particle_frames  # noqa: E402


def check(run, index):
    """The frames of one `.pvd` index, each array compared."""
    path = os.path.join(run, index)
    name = index[:-len(".pvd")]
    if name.startswith("particles"):
        frames, location = particle_frames(run, name, format="vtk"), "point"
    else:
        frames, location = field_frames(run, name, format="vtk"), "cell"
    reader = PVDReader(FileName=path)
    times = list(reader.TimestepValues) if len(frames) > 1 else [frames[0].time]
    if not np.allclose(times, [f.time for f in frames], rtol=1e-12, atol=0):
        sys.exit(f"{index}: ParaView reads times {times}, the index lists {[f.time for f in frames]}")
    for frame in frames:
        reader.UpdatePipeline(frame.time)
        # The reader's own output (pvpython runs the pipeline in this
        # process): what a ParaView user sees, without a transfer between
        # processes in between.
        data = dsa.WrapDataObject(reader.GetClientSideObject().GetOutputDataObject(0))
        arrays = data.CellData if location == "cell" else data.PointData
        for name, expected in frame.arrays.items():
            if name == "position":
                got = np.asarray(data.Points)
            else:
                got = np.asarray(arrays[name])
            # Fields: read_output gives [nz, ny, nx(, 3)]; ParaView x fastest.
            expected = np.asarray(expected).reshape(got.shape)
            if not np.array_equal(got, expected):
                sys.exit(f"{index} t = {frame.time}: {name} differs from read_output.py")
    Delete(reader)
    return len(frames)


def main():
    run = sys.argv[1]
    indices = sorted(f for f in os.listdir(run) if f.endswith(".pvd"))
    if not indices:
        sys.exit(f"{run}: no .pvd index")
    for index in indices:
        print(f"{index}: ParaView read {check(run, index)} frames as read_output.py does")


main()
