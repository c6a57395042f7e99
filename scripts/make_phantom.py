#!/usr/bin/env python3
"""Writes examples/phantom.nii.gz: a labelled phantom for `organsim mesh`.

A 40 x 40 x 30 mm box of soft tissue (label 1) holding a stiff sphere of
radius 8 mm (label 2) centred at (20, 20, 14) mm from the box's corner,
0.5 mm voxels (80 x 80 x 60), NIfTI-1 with an sform in millimetres. A voxel
is in the sphere when its centre is. Standard library only; the output is
the same bytes on every run (gzip header without a time stamp).
"""
import gzip
import struct
import sys

NX, NY, NZ = 80, 80, 60
VOXEL = 0.5  # mm
CENTRE = (20.0, 20.0, 14.0)  # mm from the box's corner
RADIUS = 8.0  # mm


def header():
    h = bytearray(352)
    struct.pack_into("<i", h, 0, 348)
    struct.pack_into("<8h", h, 40, 3, NX, NY, NZ, 1, 1, 1, 1)
    struct.pack_into("<hh", h, 70, 2, 8)  # uint8, 8 bits
    struct.pack_into("<8f", h, 76, 1.0, VOXEL, VOXEL, VOXEL, 0, 0, 0, 0)
    struct.pack_into("<ff", h, 108, 352.0, 1.0)  # vox_offset, scl_slope
    h[123] = 2  # xyz in mm
    struct.pack_into("<hh", h, 252, 0, 1)  # qform_code 0, sform_code 1
    # Voxel (0, 0, 0)'s centre half a voxel inside the box's corner at the origin.
    half = VOXEL / 2
    struct.pack_into("<4f", h, 280, VOXEL, 0, 0, half)
    struct.pack_into("<4f", h, 296, 0, VOXEL, 0, half)
    struct.pack_into("<4f", h, 312, 0, 0, VOXEL, half)
    h[344:348] = b"n+1\0"
    return bytes(h)


def labels():
    out = bytearray(NX * NY * NZ)
    n = 0
    for k in range(NZ):
        z = (k + 0.5) * VOXEL - CENTRE[2]
        for j in range(NY):
            y = (j + 0.5) * VOXEL - CENTRE[1]
            for i in range(NX):
                x = (i + 0.5) * VOXEL - CENTRE[0]
                out[n] = 2 if x * x + y * y + z * z <= RADIUS * RADIUS else 1
                n += 1
    return bytes(out)


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "examples/phantom.nii.gz"
    with open(path, "wb") as f:
        f.write(gzip.compress(header() + labels(), compresslevel=9, mtime=0))


if __name__ == "__main__":
    main()
