#!/usr/bin/env python3
"""Reads a grainflow checkpoint's state file (`rank_RRRR.state`) into a
dict of numpy arrays, by its documented layout (solvers/core/src/state.rs):

    "GRAINFLOW-STATE\\0"  format version (u32)  section count (u64)
    per section: name length (u32), name, kind (u8: 0 f64, 1 u64, 2 u32,
    3 u8), count (u64), data (little-endian)
    CRC-32 of all the bytes above (u32)  "END\\0"

usage: postprocess/read_checkpoint.py CHECKPOINT_DIR_OR_STATE_FILE
prints each section's name, kind and length.
"""
import os, struct, sys, zlib

import numpy as np

KINDS = {0: ("<f8", 8), 1: ("<u8", 8), 2: ("<u4", 4), 3: ("u1", 1)}


def read_state(path):
    data = open(path, "rb").read()
    if data[:16] != b"GRAINFLOW-STATE\0" or data[-4:] != b"END\0":
        raise ValueError(f"{path}: not a whole grainflow state")
    body, (stored,) = data[:-8], struct.unpack("<I", data[-8:-4])
    if zlib.crc32(body) != stored:
        raise ValueError(f"{path}: corrupted (checksum)")
    version, count = struct.unpack("<IQ", body[16:28])
    at, sections = 28, {}
    for _ in range(count):
        (length,) = struct.unpack("<I", body[at:at + 4]); at += 4
        name = body[at:at + length].decode(); at += length
        kind, n = struct.unpack("<BQ", body[at:at + 9]); at += 9
        dtype, width = KINDS[kind]
        sections[name] = np.frombuffer(body[at:at + n * width], dtype=dtype)
        at += n * width
    return sections


if __name__ == "__main__":
    path = sys.argv[1]
    if os.path.isdir(path):
        path = os.path.join(path, "rank_0000.state")
    for name, values in sorted(read_state(path).items()):
        print(f"{name:40s} {values.dtype}  {len(values)}")
