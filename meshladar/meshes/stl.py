"""Binary STL files read with numpy alone: the format CAD tools write most, read without
importing trimesh (half a second of the command line's start). Anything else, and an STL
whose size does not match its triangle count (ASCII, or damaged), goes to trimesh."""

from __future__ import annotations

import numpy as np

__all__ = ["STL_RECORD", "binary_stl"]

#: One triangle of a binary STL: its normal, its three corners (float32, little-endian) and
#: a 16-bit attribute word.
STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)),
                       ("attribute", "<u2")])
#: The header's length before the triangle count (bytes).
HEADER = 80


def binary_stl(path, size, head):
    """The corners and faces of a binary STL, or None when the file is not one.

    Parameters
    ----------
    path : str
        The file.
    size : int
        Its size in bytes.
    head : bytes
        Its first bytes (at least 84 when the file has them).

    Returns
    -------
    (vertices, faces) or None
        Every triangle's own three corners in file order, (3m, 3) float64, and faces
        (m, 3) int64 numbering them (as trimesh reads a binary STL unprocessed); None
        unless the size is exactly 84 + 50 m bytes with m ≥ 1 the count in the header.
    """
    if size < HEADER + 4 or len(head) < HEADER + 4:
        return None
    count = int.from_bytes(head[HEADER:HEADER + 4], "little")
    if count < 1 or size != HEADER + 4 + STL_RECORD.itemsize * count:
        return None
    records = np.fromfile(path, dtype=STL_RECORD, count=count, offset=HEADER + 4)
    vertices = records["corners"].reshape(-1, 3).astype(np.float64)
    return vertices, np.arange(3 * count, dtype=np.int64).reshape(-1, 3)
