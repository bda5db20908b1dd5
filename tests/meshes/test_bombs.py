"""Compressed mesh files unpack in bounded memory: a decompression bomb is refused as it
streams, with one line, not after filling the machine (issue 29: a 1 MB gzip STL drove the
process to 3.2 GB)."""

from __future__ import annotations

import bz2
import gzip
import tracemalloc
import zipfile

import pytest

from meshladar.errors import GeometryError
from meshladar.meshes import load_parts
from meshladar.meshes.archives import EXPANSION_FLOOR, EXPANSION_RATIO

#: The issue's bound on the peak memory while a 1 MB bomb is refused.
PEAK_LIMIT_BYTES = 500 * 2**20

_ZEROS = bytes(1 << 20)


def _bomb(path, opener, megabytes):
    with opener(path, "wb") as fh:
        for _ in range(megabytes):
            fh.write(_ZEROS)
    return path


def _peak_while_refused(path):
    tracemalloc.start()
    try:
        with pytest.raises(GeometryError, match=r"unpacks to more than \d+ MiB from \d+ "
                                                r"compressed bytes \(a decompression bomb"):
            load_parts(path)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.slow
def test_a_1_mb_gzip_bomb_is_refused_in_bounded_memory(tmp_path):
    path = _bomb(tmp_path / "bomb.stl.gz", lambda p, m: gzip.open(p, m, compresslevel=9),
                 1024)                                   # 1 GiB of zeros in ~1 MB
    assert path.stat().st_size < 1.1 * 2**20
    assert _peak_while_refused(path) < PEAK_LIMIT_BYTES


def test_a_bzip2_bomb_is_refused_past_the_floor(tmp_path):
    path = _bomb(tmp_path / "bomb.stl.bz2", bz2.open, 80)   # 80 MiB in ~100 bytes
    assert EXPANSION_RATIO * path.stat().st_size < EXPANSION_FLOOR < 80 * 2**20
    assert _peak_while_refused(path) < EXPANSION_FLOOR + 16 * 2**20


def test_a_zip_whose_members_declare_a_bomb_is_refused_before_unpacking(tmp_path):
    path = tmp_path / "bomb.zip"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        with z.open("part.stl", "w") as fh:
            for _ in range(80):
                fh.write(_ZEROS)
    assert _peak_while_refused(path) < 16 * 2**20        # nothing was unpacked


def test_an_ordinary_compressed_mesh_still_loads(tmp_path):
    import trimesh

    data = trimesh.creation.icosphere(subdivisions=3).export(file_type="stl")
    path = tmp_path / "ball.stl.gz"
    with gzip.open(path, "wb") as fh:
        fh.write(data)
    (name, mesh), = load_parts(path)
    assert len(mesh.faces) == 1280
