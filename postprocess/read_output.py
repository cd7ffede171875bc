#!/usr/bin/env python3
"""Reads grainflow's field and particle outputs into numpy arrays, from
either format a run writes:

- HDF5 (`output.format = "hdf5"`): `fields.xdmf` / `particles.xdmf` and the
  frames they list (`fields/fields_NNNNNN.h5`, `particles/...h5`), read
  with h5py;
- VTK (the default): `fields.pvd` / `particles.pvd` and the files they list
  (`.vti`, `.vtr`, `.vtp`, or the `.pvti`/`.pvtr`/`.pvtp` of a run on
  several ranks and their pieces), read by the small VTK XML reader below
  (raw appended arrays, each behind a UInt64 byte count, as grainflow
  writes them).

Both give the same Python objects:

    from read_output import field_frames, particle_frames
    for frame in field_frames("out"):      # or field_frames("out", "stretched")
        frame.time                          # [s]
        frame.arrays["pressure"]            # [nz, ny, nx]
        frame.arrays["velocity"]            # [nz, ny, nx, 3]
        frame.faces                         # [x faces, y faces, z faces]
    for frame in particle_frames("out"):
        frame.time, frame.arrays["position"]   # [n, 3]; radius [n], id [n], ...

Cell (i, j, k) is at [k, j, i] in both. A particle frame from VTK has no
`contacts` array (the VTK files do not hold it).

usage: read_output.py RUN_DIR            prints a summary of each frame
       read_output.py --compare DIR      checks that the HDF5 and VTK frames
                                         of DIR hold the same values (e.g. the
                                         sample of solvers/io/examples/
                                         hdf5_sample.rs); exits 1 if not
"""
import os
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import numpy as np


@dataclass
class Frame:
    """One output time: its arrays by name and, for fields, the face
    coordinates along x, y, z."""
    time: float
    path: str
    arrays: dict = field(default_factory=dict)
    faces: list = None


def field_frames(run, name="fields", format=None):
    """The field frames of the run folder `run`, in time order, from
    `NAME.xdmf` (HDF5) or `NAME.pvd` (VTK); `format` ("hdf5" or "vtk")
    chooses when both are there (default: HDF5)."""
    return _frames(run, name, format, _read_h5_fields, _read_vtk_fields)


def particle_frames(run, name="particles", format=None):
    """The particle frames of the run folder `run`, in time order."""
    return _frames(run, name, format, _read_h5_particles, _read_vtk_particles)


def _frames(run, name, format, read_h5, read_vtk):
    xdmf, pvd = os.path.join(run, name + ".xdmf"), os.path.join(run, name + ".pvd")
    if format is None:
        format = "hdf5" if os.path.exists(xdmf) else "vtk"
    if format == "hdf5":
        return [read_h5(t, p) for t, p in xdmf_frames(xdmf)]
    if format == "vtk":
        return [read_vtk(t, p) for t, p in pvd_frames(pvd)]
    raise ValueError(f"format {format!r}: 'hdf5' or 'vtk'")


# HDF5 + XDMF


def xdmf_frames(index):
    """(time, frame file) of each grid of an XDMF temporal collection."""
    root = ET.parse(index).getroot()
    listed = []
    for grid in root.find("Domain/Grid").findall("Grid"):
        time = float(grid.find("Time").get("Value"))
        item = grid.find("Geometry/DataItem[@Format='HDF']")
        if item is None:
            item = grid.find("Attribute/DataItem")
        path = item.text.strip().split(":")[0]
        listed.append((time, os.path.join(os.path.dirname(index), path)))
    return listed


def _read_h5_fields(time, path):
    import h5py

    with h5py.File(path, "r") as f:
        arrays = {k: f[k][()] for k in f if isinstance(f[k], h5py.Dataset)}
        faces = [f["grid"][axis][()] for axis in "xyz"]
        return Frame(float(f.attrs["time"]), path, arrays, faces)


def _read_h5_particles(time, path):
    import h5py

    with h5py.File(path, "r") as f:
        return Frame(float(f.attrs["time"]), path, {k: f[k][()] for k in f})


# VTK XML

_TYPES = {"Float64": "<f8", "Float32": "<f4", "UInt64": "<u8", "Int64": "<i8",
          "UInt32": "<u4", "Int32": "<i4", "UInt8": "u1", "Int8": "i1"}


def pvd_frames(index):
    """(time, dataset file) of each entry of a `.pvd` collection."""
    root = ET.parse(index).getroot()
    return [(float(d.get("timestep")), os.path.join(os.path.dirname(index), d.get("file")))
            for d in root.iter("DataSet")]


def _parse_vtk(path):
    """The XML root of a VTK file with raw appended data, and a function
    that reads one of its DataArray elements as numpy."""
    with open(path, "rb") as f:
        content = f.read()
    start = content.find(b'<AppendedData encoding="raw">')
    if start < 0:  # an index (.pvd, .pvti, ...): XML only
        return ET.fromstring(content), None
    root = ET.fromstring(content[:start] + b"</VTKFile>")
    block = content[content.index(b"_", start) + 1:]

    def data_array(element):
        offset = int(element.get("offset"))
        size = int(np.frombuffer(block[offset:offset + 8], "<u8")[0])
        values = np.frombuffer(block[offset + 8:offset + 8 + size], _TYPES[element.get("type")])
        components = int(element.get("NumberOfComponents", "1"))
        return values.reshape(-1, components) if components > 1 else values

    return root, data_array


def _pieces(path):
    """The piece files of a parallel index (.pvti, .pvtr, .pvtp), or the
    file itself."""
    if not os.path.basename(path).split(".")[-1].startswith("p"):
        return [path]
    root = ET.parse(path).getroot()
    return [os.path.join(os.path.dirname(path), p.get("Source")) for p in root.iter("Piece")]


def _extent(text):
    e = [int(v) for v in text.split()]
    return e[0::2], e[1::2]


def _read_vtk_fields(time, path):
    root, _ = _parse_vtk(path)
    dataset = root[0]
    lower, upper = _extent(dataset.get("WholeExtent"))
    cells = [u - l for l, u in zip(lower, upper)]
    arrays, faces = {}, [None] * 3
    if dataset.get("Origin") is not None:
        origin = [float(v) for v in dataset.get("Origin").split()]
        spacing = [float(v) for v in dataset.get("Spacing").split()]
        faces = [origin[a] + spacing[a] * np.arange(cells[a] + 1) for a in range(3)]
    for piece_path in _pieces(path):
        piece_root, _data_array = _parse_vtk(piece_path)
        piece = piece_root[0].find("Piece")
        start, end = _extent(piece.get("Extent"))
        n = [e - s for s, e in zip(start, end)]
        coordinates = piece.find("Coordinates")
        if coordinates is not None:
            for a, item in enumerate(coordinates.findall("DataArray")):
                if faces[a] is None:
                    faces[a] = np.zeros(cells[a] + 1)
                faces[a][start[a]:end[a] + 1] = _data_array(item)
        for item in piece.find("CellData").findall("DataArray"):
            values = _data_array(item)
            shape = (n[2], n[1], n[0]) + values.shape[1:]
            whole = arrays.setdefault(
                item.get("Name"), np.zeros((cells[2], cells[1], cells[0]) + values.shape[1:]))
            whole[start[2]:end[2], start[1]:end[1], start[0]:end[0]] = values.reshape(shape)
    return Frame(time, path, arrays, faces)


def _read_vtk_particles(time, path):
    arrays = {}
    for piece_path in _pieces(path):
        root, _data_array = _parse_vtk(piece_path)
        piece = root.find("PolyData/Piece")
        found = {"position": _data_array(piece.find("Points/DataArray"))}
        for item in piece.find("PointData").findall("DataArray"):
            found[item.get("Name")] = _data_array(item)
        for k, v in found.items():
            arrays.setdefault(k, []).append(v)
    return Frame(time, path, {k: np.concatenate(v) for k, v in arrays.items()})


# Command line


def _summary(run):
    for kind, frames in [("fields", field_frames), ("particles", particle_frames)]:
        for name in sorted(os.listdir(run)):
            stem, ext = os.path.splitext(name)
            if ext not in (".xdmf", ".pvd") or (kind == "fields") == (stem == "particles"):
                continue
            for frame in frames(run, stem, "hdf5" if ext == ".xdmf" else "vtk"):
                shapes = ", ".join(f"{k} {v.shape}" for k, v in sorted(frame.arrays.items()))
                print(f"{name} t = {frame.time:g}: {shapes}")


def _compare(run):
    """Whether every index of `run` in both formats holds the same frames."""
    failures, checked = [], 0
    names = sorted({os.path.splitext(n)[0] for n in os.listdir(run) if n.endswith(".xdmf")})
    for stem in names:
        if not os.path.exists(os.path.join(run, stem + ".pvd")):
            continue
        read = particle_frames if stem == "particles" else field_frames
        h5, vtk = read(run, stem, "hdf5"), read(run, stem, "vtk")
        checked += 1
        problems = []
        if [f.time for f in h5] != [f.time for f in vtk]:
            problems.append(f"times {[f.time for f in h5]} against {[f.time for f in vtk]}")
        for a, b in zip(h5, vtk):
            for key in sorted(set(a.arrays) & set(b.arrays)):
                if not np.array_equal(a.arrays[key], b.arrays[key]):
                    problems.append(f"t = {a.time}: {key} differs")
            missing = set(b.arrays) - set(a.arrays)
            if missing:
                problems.append(f"t = {a.time}: HDF5 lacks {sorted(missing)}")
            if a.faces is not None and any(
                    not np.allclose(x, y, rtol=1e-15, atol=0) for x, y in zip(a.faces, b.faces)):
                problems.append(f"t = {a.time}: face coordinates differ")
        print(f"{stem}: {len(h5)} frames, " + ("the same in both formats" if not problems
                                                else "; ".join(problems)))
        if problems:
            failures.append(stem)
    print(f"read_output compare: {checked - len(failures)} passed, {len(failures)} failed")
    return not failures and checked > 0


if __name__ == "__main__":
    arguments = sys.argv[1:]
    if arguments[:1] == ["--compare"] and len(arguments) == 2:
        sys.exit(0 if _compare(arguments[1]) else 1)
    if len(arguments) != 1:
        print(__doc__)
        sys.exit(2)
    _summary(arguments[0])
