"""Opens grainflow's XDMF indices in ParaView's XDMF 3 reader and checks
that what ParaView reads is what the HDF5 frames hold: the times, every
cell or point array (values, components, order), the grid's geometry and
the grains' positions. The HDF5 side is read with h5py.

usage: pvpython tests/paraview_xdmf.py [--sample] DIR [INDEX.xdmf ...]
    (default: every *.xdmf in DIR). Exits 1 on a mismatch. With --sample,
    the arrays are also checked against the values the sample writer
    computes (`solvers/io/examples/hdf5_sample.rs`), not only against the
    HDF5 files.

CI runs it on the sample written by
`cargo run -p grainflow-io --features hdf5 --example hdf5_sample -- DIR`
(Debian's `paraview` and `python3-h5py` packages).
"""
import glob
import os
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np
from paraview.simple import Delete, Xdmf3ReaderS
from vtkmodules.numpy_interface import dataset_adapter as dsa


def frames(index):
    """(time, h5 file, grid element) of each frame listed in the index."""
    root = ET.parse(index).getroot()
    collection = root.find("Domain/Grid")
    assert collection.get("GridType") == "Collection", index
    assert collection.get("CollectionType") == "Temporal", index
    listed = []
    for grid in collection.findall("Grid"):
        time = float(grid.find("Time").get("Value"))
        item = grid.find("Attribute/DataItem")
        if item is None:
            item = grid.find("Geometry/DataItem")
        path = item.text.strip().split(":")[0]
        listed.append((time, os.path.join(os.path.dirname(index), path), grid))
    return listed


def first_block(data):
    """The dataset itself, or the first leaf of a multiblock."""
    while data.IsA("vtkMultiBlockDataSet") or data.IsA("vtkPartitionedDataSetCollection"):
        data = data.GetBlock(0)
    return data


def check_frame(reader, time, h5, grid, problems, label, sample=False):
    reader.UpdatePipeline(time)
    # The reader's own output (pvpython runs it in process): Fetch's copy
    # of a rectilinear grid garbles its coordinates in ParaView 5.11.
    data = first_block(reader.GetClientSideObject().GetOutputDataObject(0))
    wrapped = dsa.WrapDataObject(data)
    topology = grid.find("Topology").get("TopologyType")
    with h5py.File(h5, "r") as f:
        written = float(f.attrs["time"])
        if written != time:
            problems.append(f"{label}: index time {time} but frame time {written}")
        if topology == "Polyvertex":
            arrays = wrapped.PointData
            expected_points = f["position"][()]
            points = wrapped.Points
            # A frame without grains opens as an empty dataset, no arrays.
            points = np.zeros((0, 3)) if points is None else np.asarray(points)
            if points.shape != expected_points.shape or not np.array_equal(points, expected_points):
                problems.append(f"{label}: points differ from position")
            if sample:
                known = sample_value("position", expected_points.shape, time, True)
                if not np.array_equal(known, points):
                    problems.append(f"{label}: points are not what the sample wrote")
        else:
            arrays = wrapped.CellData
            check_geometry(data, f, grid, problems, label)
        for attribute in grid.findall("Attribute"):
            name = attribute.get("Name")
            expected = f[name][()]
            read = arrays[name]
            if read is None or isinstance(read, dsa.VTKNoneArray):
                if expected.size == 0:
                    continue
                problems.append(f"{label}: ParaView read no array {name}")
                continue
            read = np.asarray(read)
            if sample:
                known = sample_value(name, expected.shape, time, topology == "Polyvertex")
                if known is not None and not np.array_equal(known, expected):
                    problems.append(f"{label}: {name} is not what the sample wrote")
            components = 3 if attribute.get("AttributeType") == "Vector" else 1
            expected = expected.reshape(-1, components) if components == 3 else expected.reshape(-1)
            if read.shape != expected.shape:
                problems.append(f"{label}: {name} shape {read.shape}, written {expected.shape}")
            elif not np.array_equal(read.astype(np.float64), expected.astype(np.float64)):
                worst = np.max(np.abs(read.astype(np.float64) - expected.astype(np.float64)))
                problems.append(f"{label}: {name} differs (largest difference {worst})")
    return data


FIELDS = {"pressure": 0, "solid_fraction": 1, "velocity": 2, "vorticity": 3}
PARTICLES = {"position": 0.1, "velocity": -1.0, "angular_velocity": 2.0, "force": 0.5}


def sample_value(name, shape, time, points):
    """What hdf5_sample.rs writes for array `name` of `shape` at `time`."""
    if points:
        if name not in PARTICLES:
            return None
        k = np.arange(shape[0])[:, None]
        return PARTICLES[name] * k + np.arange(3)[None, :] + time
    k, j, i = np.meshgrid(*[np.arange(n) for n in shape[:3]], indexing="ij")
    base = 100.0 * FIELDS[name] + i + 10.0 * j + 0.01 * k + time
    if len(shape) == 4:
        return np.stack([base + 1000.0 * c for c in range(3)], axis=-1)
    return base


def check_geometry(data, f, grid, problems, label):
    """Cell counts and face coordinates of a field frame's grid."""
    faces = [f["grid"][axis][()] for axis in "xyz"]
    cells = [len(c) - 1 for c in faces]
    if data.GetNumberOfCells() != np.prod(cells):
        problems.append(f"{label}: {data.GetNumberOfCells()} cells, written {cells}")
    if data.IsA("vtkRectilinearGrid"):
        read = [data.GetXCoordinates(), data.GetYCoordinates(), data.GetZCoordinates()]
        for axis, (r, w) in enumerate(zip(read, faces)):
            r = np.array([r.GetValue(i) for i in range(r.GetNumberOfTuples())])
            if not np.array_equal(r, w):
                problems.append(f"{label}: face coordinates along axis {axis} differ")
    else:
        bounds = data.GetBounds()
        for axis in range(3):
            lower, upper = bounds[2 * axis], bounds[2 * axis + 1]
            if not (np.isclose(lower, faces[axis][0]) and np.isclose(upper, faces[axis][-1])):
                problems.append(
                    f"{label}: bounds along axis {axis} {lower, upper}, "
                    f"faces {faces[axis][0], faces[axis][-1]}"
                )


def check_index(index, sample):
    problems = []
    listed = frames(index)
    reader = Xdmf3ReaderS(FileName=[index])
    reader.UpdatePipelineInformation()
    times = list(reader.TimestepValues) if len(listed) > 1 else [listed[0][0]]
    if not np.array_equal(np.array(times, dtype=float), np.array([t for t, _, _ in listed])):
        problems.append(f"{index}: ParaView's times {times}, listed {[t for t, _, _ in listed]}")
    for n, (time, h5, grid) in enumerate(listed):
        label = f"{os.path.basename(index)} frame {n}"
        check_frame(reader, time, h5, grid, problems, label, sample)
    Delete(reader)
    print(f"{index}: {len(listed)} frames at t = {times}: "
          + ("as written" if not problems else f"{len(problems)} problems"))
    return problems


def main():
    arguments = sys.argv[1:]
    sample = "--sample" in arguments
    arguments = [a for a in arguments if a != "--sample"]
    if not arguments:
        print(__doc__)
        sys.exit(2)
    directory = arguments[0]
    indices = arguments[1:] or sorted(glob.glob(os.path.join(directory, "*.xdmf")))
    if not indices:
        print(f"no .xdmf index in {directory}")
        sys.exit(1)
    problems = []
    for index in indices:
        if not os.path.exists(index):
            index = os.path.join(directory, index)
        problems += check_index(index, sample)
    for p in problems:
        print("  " + p)
    failed = len({p.split(" frame")[0] for p in problems})
    print(f"paraview xdmf: {len(indices) - failed} passed, {failed} failed")
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
