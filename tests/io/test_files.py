"""Users' own mesh files: every file trimesh reads loads, everything else is one clear line.

A small corpus of real-world-shaped files, written here into ``tmp_path`` (no network), goes
through the API (``Scene.from_mesh``) and the command line (``meshladar simulate FILE``):
a loadable file gives the faces and area that were written, anything else a GeometryError
(API) or exit status 2 with one ``meshladar: error:`` line (CLI), never a traceback.
"""

from __future__ import annotations

import bz2
import gzip
import importlib.machinery
import importlib.util
import json
import lzma
import math
import struct
import subprocess
import sys
import tarfile
import zipfile
import zlib
from dataclasses import dataclass

import numpy as np
import pytest
import trimesh

import meshladar as ml
from meshladar import cli
from meshladar import io as mlio
from meshladar.errors import GeometryError
from meshladar.materials import DARK_GRAY
from meshladar.meshes import corner_normals, MeshPart

BOX = 0.5                    # edge of the test box: 12 faces, area 6·0.5² = 1.5
BOX_AREA = 6 * BOX * BOX


# ------------------------------------------------------------------ the corpus

def _png(width=2, height=2):
    """A tiny RGB PNG written by hand (zlib + struct), so no test needs Pillow."""
    raw = b"".join(b"\x00" + bytes([200, 30, 30] * width) for _ in range(height))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    return (b"\x89PNG\r\n\x1a\n"
            + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def _box():
    return trimesh.creation.box(extents=(BOX, BOX, BOX))


def _stl_bytes():
    return _box().export(file_type="stl")


def _textured_obj(folder, name="box", *, mtl=True):
    """A box as exporters write a UV-mapped mesh: shared positions, a texture coordinate per
    face corner (so every vertex is split at a UV seam), a .mtl naming a PNG texture."""
    box = _box()
    lines = [f"mtllib {name}.mtl", "usemtl skin"] if mtl else []
    lines += [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in box.vertices]
    lines += [f"vt {(k % 7) / 7:.6f} {(k % 5) / 5:.6f}" for k in range(3 * len(box.faces))]
    lines += ["f " + " ".join(f"{f[c] + 1}/{3 * i + c + 1}" for c in range(3))
              for i, f in enumerate(box.faces)]
    (folder / f"{name}.obj").write_text("\n".join(lines) + "\n")
    if mtl:
        (folder / f"{name}.mtl").write_text("newmtl skin\nKd 0.8 0.8 0.8\nmap_Kd skin.png\n")
        (folder / "skin.png").write_bytes(_png())
    return folder / f"{name}.obj"


def _textured_ply(folder):
    """A PLY with per-vertex texture coordinates and a TextureFile comment."""
    box = _box()
    head = ["ply", "format ascii 1.0", "comment TextureFile skin.png",
            f"element vertex {len(box.vertices)}", "property float x", "property float y",
            "property float z", "property float s", "property float t",
            f"element face {len(box.faces)}", "property list uchar int vertex_indices",
            "end_header"]
    body = [f"{x:.9g} {y:.9g} {z:.9g} {k / 8:.3f} {1 - k / 8:.3f}"
            for k, (x, y, z) in enumerate(box.vertices)]
    body += [f"3 {a} {b} {c}" for a, b, c in box.faces]
    (folder / "skin.png").write_bytes(_png())
    path = folder / "textured.ply"
    path.write_text("\n".join(head + body) + "\n")
    return path


def _two_part_glb(path):
    sc = trimesh.Scene()
    sc.add_geometry(_box(), node_name="box",
                    transform=trimesh.transformations.translation_matrix([-0.6, 0, 0]))
    sc.add_geometry(trimesh.creation.icosphere(subdivisions=1, radius=0.25), node_name="ball",
                    transform=trimesh.transformations.translation_matrix([0.6, 0, 0]))
    sc.export(path)
    return path


def _write(name, data):
    def write(folder):
        path = folder / name
        path.write_bytes(data() if callable(data) else data)
        return path
    return write


def _export(name, **kw):
    def write(folder):
        path = folder / name
        _box().export(path, **kw)
        return path
    return write


def _zip_of(name, members):
    def write(folder):
        path = folder / name
        with zipfile.ZipFile(path, "w") as z:
            for inner, data in members().items():
                z.writestr(inner, data)
        return path
    return write


def _tar_gz(folder):
    (folder / "inner").mkdir()
    (folder / "inner" / "box.stl").write_bytes(_stl_bytes())
    path = folder / "box.tar.gz"
    with tarfile.open(path, "w:gz") as t:
        t.add(folder / "inner" / "box.stl", arcname="box.stl")
    return path


def _point_cloud_ply(folder):
    path = folder / "scan.ply"
    pts = np.random.default_rng(7).random((50, 3))
    path.write_bytes(trimesh.PointCloud(pts).export(file_type="ply"))
    return path


def _point_cloud_glb(folder):
    path = folder / "scan.glb"
    sc = trimesh.Scene()
    sc.add_geometry(trimesh.PointCloud(np.random.default_rng(8).random((20, 3))),
                    node_name="scan")
    sc.export(path)
    return path


def _drawing_dxf(folder):
    path = folder / "outline.dxf"
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], dtype=float)
    trimesh.load_path(square).export(str(path))
    return path


def _nan_obj(folder):
    path = folder / "nan.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 nan 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n")
    return path


def _dae(folder):
    path = folder / "box.dae"
    if importlib.util.find_spec("collada") is None:
        path.write_text('<?xml version="1.0"?>\n<COLLADA xmlns="http://www.collada.org/2005/'
                        '11/COLLADASchema" version="1.4.1"></COLLADA>\n')
    else:
        _box().export(path)
    return path


def _3mf(folder):
    path = folder / "box.3mf"
    if _has("lxml", "networkx"):
        _box().export(path)
    else:
        with zipfile.ZipFile(path, "w") as z:
            z.writestr("3D/3dmodel.model", "<model/>")
    return path


def _has(*modules):
    return all(importlib.util.find_spec(m) is not None for m in modules)


@dataclass(frozen=True)
class Mesh:
    """A loadable file: faces, total area and part names it must give (None: one part,
    named as trimesh names it)."""
    faces: int
    area: float
    parts: tuple | None = None


@dataclass(frozen=True)
class Fails:
    """A file that must give one GeometryError line matching ``what`` (and its name)."""
    what: str


_RNG_BYTES = np.random.default_rng(2024).bytes(3000)
_BALL = trimesh.creation.icosphere(subdivisions=1, radius=0.25)

CORPUS = {
    "textured OBJ + mtl + PNG": (lambda d: _textured_obj(d), Mesh(12, BOX_AREA)),
    "binary STL": (_export("box.stl"), Mesh(12, BOX_AREA)),
    "ASCII STL": (_write("box_ascii.stl", lambda: trimesh.exchange.stl.export_stl_ascii(_box())
                         .encode()), Mesh(12, BOX_AREA)),
    "zipped STL": (_zip_of("box.zip", lambda: {"box.stl": _stl_bytes()}),
                   Mesh(12, BOX_AREA)),
    "gzip STL": (_write("box.stl.gz", lambda: gzip.compress(_stl_bytes())),
                 Mesh(12, BOX_AREA)),
    "bzip2 STL": (_write("box.stl.bz2", lambda: bz2.compress(_stl_bytes())),
                  Mesh(12, BOX_AREA)),
    "xz STL": (_write("box.stl.xz", lambda: lzma.compress(_stl_bytes())),
               Mesh(12, BOX_AREA)),
    "tar.gz STL": (_tar_gz, Mesh(12, BOX_AREA)),
    "two-part GLB": (lambda d: _two_part_glb(d / "parts.glb"),
                     Mesh(12 + 80, BOX_AREA + _BALL.area, ("box", "ball"))),
    "binary PLY": (_export("box_bin.ply", encoding="binary"), Mesh(12, BOX_AREA)),
    "ASCII PLY": (_export("box_ascii.ply", encoding="ascii"), Mesh(12, BOX_AREA)),
    "textured PLY": (_textured_ply, Mesh(12, BOX_AREA)),
    "OFF": (_export("box.off"), Mesh(12, BOX_AREA)),
    # the format comes from the content when the suffix says nothing
    "binary STL named .dat": (_write("scan.dat", _stl_bytes), Mesh(12, BOX_AREA)),
    "ASCII STL named .txt": (_write("box.txt", lambda: trimesh.exchange.stl.export_stl_ascii(
        _box()).encode()), Mesh(12, BOX_AREA)),
    "PLY point cloud": (_point_cloud_ply, Fails(r"point cloud \(50 points, no faces\)")),
    "GLB of points only": (_point_cloud_glb, Fails(r"point cloud \(20 points, no faces\)")),
    "2-D DXF drawing": (_drawing_dxf, Fails(r"2-D drawing .*not a 3-D triangle mesh")),
    "empty file": (_write("empty.stl", b""), Fails(r"empty file")),
    "whitespace only": (_write("blank.obj", b"\n \n\t\n"), Fails(r"empty file")),
    "binary junk .stl": (_write("junk.stl", _RNG_BYTES),
                         Fails(r"not a readable STL file .*binary data")),
    "binary junk .xyz": (_write("junk.xyz", _RNG_BYTES), Fails(r"not a readable XYZ")),
    "binary junk .bin": (_write("junk.bin", _RNG_BYTES),
                         Fails(r"unknown file format '\.bin'.*binary data")),
    "text, unknown suffix": (_write("notes.txt", b"measured on 2024-05-01\nall good\n"),
                             Fails(r"unknown file format '\.txt'.*\(text\)")),
    "corrupt gzip": (_write("box.stl.gz", b"\x1f\x8b\x08" + _RNG_BYTES[:40]),
                     Fails(r"not a valid gzip file")),
    "zip without meshes": (_zip_of("docs.zip", lambda: {"readme.txt": b"hello"}),
                           Fails(r"holds no file trimesh reads as geometry \(files: "
                                 r"readme\.txt\)")),
    "NaN vertex": (_nan_obj, Fails(r"vertices must be finite")),
    "missing file": (lambda d: d / "nope.stl", Fails(r"no such mesh file")),
    "COLLADA": (_dae, Mesh(12, BOX_AREA) if _has("collada")
                else Fails(r"needs the optional package pycollada: pip install pycollada")),
    "3MF": (_3mf, Mesh(12, BOX_AREA) if _has("lxml", "networkx")
            else Fails(r"needs the optional package" + ("s lxml and networkx"
                                                          if not _has("networkx")
                                                          else " lxml: pip install lxml"))),
}

#: Face areas from coordinates stored as float32 (STL, GLB, binary PLY) or printed with 9
#: significant digits: relative error about 2⁻²³ per coordinate, so 1e-6 on an area.
AREA_RTOL = 1e-6


def _area(scene):
    return sum(float(p.face_normals_areas()[1].sum()) for p in scene.parts)


@pytest.mark.parametrize("case", list(CORPUS))
def test_api_loads_or_says_what_is_wrong(tmp_path, case):
    write, expected = CORPUS[case]
    path = write(tmp_path)
    if isinstance(expected, Mesh):
        scene = ml.Scene.from_mesh(path, DARK_GRAY)
        assert scene.report["faces"] == expected.faces
        assert _area(scene) == pytest.approx(expected.area, rel=AREA_RTOL)
        names = tuple(p.name for p in scene.parts)
        assert sorted(names) == sorted(expected.parts) if expected.parts else len(names) == 1
        # welded by position: closed solids are closed again, whatever the file split
        assert all(scene.report["watertight"]) and scene.report["degenerate_faces"] == 0
        return
    with pytest.raises(GeometryError) as info:
        ml.Scene.from_mesh(path, DARK_GRAY)
    msg = str(info.value)
    assert "\n" not in msg and "\r" not in msg and len(msg) < 600
    assert path.name in msg
    assert info.match(expected.what)


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # faceted on purpose
@pytest.mark.parametrize("case", list(CORPUS))
def test_cli_simulates_or_prints_one_error_line(tmp_path, case, capsys):
    write, expected = CORPUS[case]
    path = write(tmp_path)
    out = tmp_path / "out.npz"
    code = cli.main(["simulate", str(path), "-o", str(out), "--views", "4", "--bins", "16",
                     "--bin-width", "0.2", "--quiet"])
    captured = capsys.readouterr()
    if isinstance(expected, Mesh):
        assert code == 0 and captured.err == ""
        sino, meta = mlio.load_sinogram(out)
        assert sino.values.shape == (4, 16) and meta["params"]["model"] == "mesh"
        assert np.all(np.isfinite(sino.values)) and np.all(sino.total() > 0)
        return
    assert code == 2 and not out.exists()
    lines = [line for line in captured.err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("meshladar: error:")
    assert path.name in lines[0]


def test_multi_part_glb_keeps_each_part_where_it_was_placed(tmp_path):
    scene = ml.Scene.from_mesh(_two_part_glb(tmp_path / "parts.glb"),
                               materials={"box": DARK_GRAY, "ball": ml.materials.ALUMINUM})
    parts = {p.name: p for p in scene.parts}
    box, ball = parts["box"], parts["ball"]
    assert scene.materials[box.material[0]] is DARK_GRAY
    assert scene.materials[ball.material[0]] is ml.materials.ALUMINUM
    # float32 storage in the GLB: 1e-6 on coordinates of order 1
    place = 1e-6
    np.testing.assert_allclose(box.vertices.mean(axis=0), [-0.6, 0, 0], atol=place)
    np.testing.assert_allclose(np.linalg.norm(ball.vertices - [0.6, 0, 0], axis=1), 0.25,
                               atol=place)


def _tetrahedron_lines(first, x0):
    """An OBJ's lines for a closed tetrahedron at x = x0 whose vertices start at ``first``."""
    a, b, c, d = range(first, first + 4)
    return [f"v {x0} 0 0", f"v {x0 + 1} 0 0", f"v {x0} 1 0", f"v {x0} 0 1",
            f"f {a} {c} {b}", f"f {a} {b} {d}", f"f {a} {d} {c}", f"f {b} {c} {d}"]


def _two_object_obj(path):
    """An OBJ of two named objects ('o left', 'o right'), a tetrahedron each, 3 apart."""
    path.write_text("\n".join(["# two objects", "o left", *_tetrahedron_lines(1, 0.0),
                               "o right", *_tetrahedron_lines(5, 3.0)]) + "\n")
    return path


def test_named_objects_of_an_obj_are_parts_coated_separately(tmp_path, capsys):
    path = _two_object_obj(tmp_path / "pair.obj")
    scene = ml.Scene.from_mesh(path, material=DARK_GRAY,
                               materials={"left": ml.materials.ALUMINUM, "right": DARK_GRAY})
    assert [p.name for p in scene.parts] == ["left", "right"]       # in file order
    left, right = scene.parts
    assert len(left.faces) == len(right.faces) == 4
    assert scene.materials[left.material[0]] is ml.materials.ALUMINUM
    assert scene.materials[right.material[0]] is DARK_GRAY
    np.testing.assert_array_equal(left.vertices.min(axis=0), [0, 0, 0])
    np.testing.assert_array_equal(right.vertices.min(axis=0), [3, 0, 0])
    # the command line coats one object by its name: coating both by name is coating all
    def simulate(name, *flags):
        out = tmp_path / f"{name}.npz"
        code = cli.main(["simulate", str(path), "-o", str(out), "--views", "4", "--bins",
                         "16", "--bin-width", "0.5", "--quiet", *flags])
        assert code == 0 and capsys.readouterr().err == ""
        return mlio.load_sinogram(out)

    left_al, meta = simulate("left", "--coating", "left=aluminum")
    assert [p["name"] for p in meta["scene"]["parts"]] == ["left", "right"]
    assert {m["name"] for m in meta["scene"]["materials"]} == {"aluminum", "dark_gray"}
    plain, _ = simulate("plain")
    both, _ = simulate("both", "--coating", "left=aluminum,right=aluminum")
    all_al, _ = simulate("all", "--material", "aluminum")
    np.testing.assert_array_equal(both.values, all_al.values)
    assert not np.array_equal(left_al.values, plain.values)
    assert not np.array_equal(left_al.values, all_al.values)
    # a part trimesh splits off an object by material follows its object
    (tmp_path / "mtl.obj").write_text(path.read_text().replace("f 1 4 3", "usemtl b\nf 1 4 3"))
    names = [p.name for p in ml.Scene.from_mesh(tmp_path / "mtl.obj", DARK_GRAY).parts]
    assert names[0] == "left" and names[-1] == "right" and len(names) == 3
    # one named object is a part of that name (a glTF's single node is too)
    (tmp_path / "one.obj").write_text("o left\n" + "\n".join(_tetrahedron_lines(1, 0.0)))
    assert [p.name for p in ml.Scene.from_mesh(tmp_path / "one.obj", DARK_GRAY).parts] == [
        "left"]


def test_not_a_mesh_in_memory_says_what_it_is():
    wire = trimesh.load_path(np.array([[0, 0, 0], [1, 0, 1], [1, 1, 2]], dtype=float))
    with pytest.raises(GeometryError, match=r"^mesh: holds a 3-D path \(1 line or curve, "
                                            r"no faces\), not a triangle mesh$"):
        ml.Scene.from_mesh(wire, DARK_GRAY)
    sc = trimesh.Scene()
    sc.add_geometry(trimesh.PointCloud(np.eye(3)), node_name="scan")
    sc.add_geometry(wire, node_name="wire")
    with pytest.raises(GeometryError, match=r"the scene holds no triangle meshes \(only a "
                                            r"point cloud \(3 points, no faces\), a 3-D path"):
        ml.Scene.from_mesh(sc, DARK_GRAY)
    with pytest.raises(GeometryError, match=r"expected a triangle mesh or a scene of meshes; "
                                            r"got list"):
        ml.Scene.from_mesh([1, 2, 3], DARK_GRAY)


def test_reader_errors_become_one_chained_line(tmp_path, monkeypatch):
    path = tmp_path / "box.stl"                   # ASCII: trimesh reads it (binary: numpy)
    path.write_bytes(_box().export(file_type="stl_ascii").encode())
    boom = ValueError("first line\n\n   second line\twith tabs " + "x" * 5000)

    def broken(*args, **kwargs):
        raise boom

    monkeypatch.setattr(trimesh, "load", broken)
    with pytest.raises(GeometryError) as info:
        ml.Scene.from_mesh(path, DARK_GRAY)
    msg = str(info.value)
    assert msg.startswith(f"{path}: not a readable STL file (ValueError: first line second "
                          "line with tabs xxx")
    assert "\n" not in msg and len(msg) < len(str(path)) + 250 and msg.endswith("...)")
    assert info.value.__cause__ is boom


def test_a_missing_reader_package_is_named_by_the_readers_import_error(tmp_path, monkeypatch):
    # cube1.3dxml: lxml and networkx installed (trimesh registers the reader), Pillow not;
    # the reader's ImportError names PIL, whose pip package is Pillow
    from meshladar.meshes import formats

    path = tmp_path / "cube1.3dxml"
    path.write_bytes(b"PK\x03\x04" + b"\x00" * 200)
    real_find_spec = importlib.util.find_spec

    def find_spec(name, *args):
        if name in ("lxml", "networkx"):
            return importlib.machinery.ModuleSpec(name, None)
        return None if name.split(".")[0] == "PIL" else real_find_spec(name, *args)

    monkeypatch.setattr(importlib.util, "find_spec", find_spec)
    monkeypatch.setattr(formats, "_readable_formats",
                        lambda: set(trimesh.available_formats()) | {"3dxml"})
    error = ModuleNotFoundError("No module named 'PIL'", name="PIL")

    def load(*args, **kwargs):
        raise error

    monkeypatch.setattr(trimesh, "load", load)
    with pytest.raises(GeometryError) as info:
        ml.Scene.from_mesh(path, DARK_GRAY)
    assert str(info.value) == (f"{path}: reading '.3dxml' files needs the optional package "
                               "Pillow: pip install Pillow")
    assert info.value.__cause__ is error
    # an ImportError from a package that is there is not a missing package: quote it
    error = ImportError("cannot import name 'tree' from 'networkx'", name="networkx")
    with pytest.raises(GeometryError, match=r"needs a package that is not installed "
                                            r"\(cannot import name 'tree' from 'networkx'\)$"):
        ml.Scene.from_mesh(path, DARK_GRAY)


def test_what_a_reader_prints_stays_off_the_terminal_unless_the_file_fails(
        tmp_path, monkeypatch, capfd):
    # meshio prints "Error: Couldn't read file ... as ansys" while it tries formats
    path = tmp_path / "box.stl"                   # ASCII: trimesh reads it (binary: numpy)
    path.write_bytes(_box().export(file_type="stl_ascii").encode())
    real_load = trimesh.load
    outcome = {"fail": False}

    def chatty(*args, **kwargs):
        print("Error: Couldn't read file box.stl as ansys", file=sys.stderr)
        print("Error: Couldn't read file box.stl as avsucd")
        if outcome["fail"]:
            raise ValueError("not a mesh")
        return real_load(*args, **kwargs)

    monkeypatch.setattr(trimesh, "load", chatty)
    scene = ml.Scene.from_mesh(path, DARK_GRAY)
    assert scene.report["faces"] == 12
    assert capfd.readouterr() == ("", "")
    outcome["fail"] = True
    with pytest.raises(GeometryError) as info:
        ml.Scene.from_mesh(path, DARK_GRAY)
    assert capfd.readouterr() == ("", "")
    assert str(info.value) == (f"{path}: not a readable STL file (ValueError: not a mesh) "
                               "(the reader printed: Error: Couldn't read file box.stl as "
                               "ansys Error: Couldn't read file box.stl as avsucd)")


def test_in_memory_meshes_are_not_changed_by_loading():
    sc = trimesh.Scene()
    box = _box()
    sc.add_geometry(box, node_name="box",
                    transform=trimesh.transformations.translation_matrix([3.0, 0, 0]))
    before = box.vertices.copy()
    scene = ml.Scene.from_mesh(sc, DARK_GRAY)
    np.testing.assert_array_equal(box.vertices, before)
    assert scene.bounds()[0, 0] == pytest.approx(3.0 - BOX / 2)


# ------------------------------------------------------------------ no Pillow needed

_NO_PIL = """
import json, sys

class NoPIL:
    attempts = []
    def find_spec(self, name, path=None, target=None):
        if name == "PIL" or name.startswith("PIL."):
            NoPIL.attempts.append(name)
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None

sys.meta_path.insert(0, NoPIL())
import trimesh
import meshladar as ml
NoPIL.attempts.clear()              # trimesh tries Pillow on import, guarded; loading must not
out = {}
for path in sys.argv[1:]:
    scene = ml.Scene.from_mesh(path, ml.materials.DARK_GRAY)
    out[path] = [scene.report["faces"], all(scene.report["watertight"])]
print(json.dumps({"loaded": out, "pil_imports": NoPIL.attempts}))
"""


@pytest.mark.slow
def test_textured_meshes_load_without_pillow(tmp_path):
    paths = [_textured_obj(tmp_path, "box"), _textured_obj(tmp_path, "lost", mtl=False),
             _textured_ply(tmp_path), _two_part_glb(tmp_path / "parts.glb")]
    (tmp_path / "lost.obj").write_text("mtllib missing.mtl\nusemtl skin\n"
                                       + (tmp_path / "lost.obj").read_text())
    res = subprocess.run([sys.executable, "-c", _NO_PIL, *map(str, paths)],
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    report = json.loads(res.stdout)
    assert report["pil_imports"] == []
    assert report["loaded"] == {str(p): [f, True] for p, f in zip(paths, [12, 12, 12, 92])}


# ------------------------------------------------------------------ welding and normals

def _uv_sphere_obj(path, n_lat, n_lon):
    """A unit latitude-longitude sphere as a UV-mapped OBJ: positions once each, texture
    coordinates on an (n_lat + 1) × (n_lon + 1) grid, so the loader splits every vertex on
    the seam meridian and every pole vertex once per column (as exporters write them)."""
    def vid(i, j):                    # 1-based position index of ring i, column j
        if i == 0:
            return 1
        if i == n_lat:
            return 2 + (n_lat - 1) * n_lon
        return 2 + (i - 1) * n_lon + j % n_lon

    lines = ["v 0 0 1"]
    for i in range(1, n_lat):
        th = math.pi * i / n_lat
        lines += [f"v {math.sin(th) * math.cos(ph):.17g} {math.sin(th) * math.sin(ph):.17g} "
                  f"{math.cos(th):.17g}" for ph in 2 * math.pi * np.arange(n_lon) / n_lon]
    lines.append("v 0 0 -1")
    lines += [f"vt {j / n_lon:.6f} {1 - i / n_lat:.6f}"
              for i in range(n_lat + 1) for j in range(n_lon + 1)]
    for i in range(n_lat):
        for j in range(n_lon):
            a, b, c, d = (i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)
            tris = [(a, b, c)] if i == 0 else [(a, b, d)] if i == n_lat - 1 else \
                [(a, b, d), (b, c, d)]
            lines += ["f " + " ".join(f"{vid(*p)}/{1 + p[0] * (n_lon + 1) + p[1]}" for p in t)
                      for t in tris]
    path.write_text("\n".join(lines) + "\n")
    return path


def _angle_to_sphere_deg(part):
    """(m, 3) angle between each corner normal and the exact normal of the unit sphere."""
    exact = part.vertices[part.faces]
    exact = exact / np.linalg.norm(exact, axis=-1, keepdims=True)
    cos = np.einsum("fck,fck->fc", corner_normals(part), exact)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def test_uv_seams_are_not_creases(tmp_path):
    n_lat, n_lon = 16, 32
    path = _uv_sphere_obj(tmp_path / "globe.obj", n_lat, n_lon)
    raw = trimesh.load(path, process=False)            # as the file splits it
    assert len(raw.vertices) > 2 + (n_lat - 1) * n_lon   # the seams exist in the file
    scene = ml.Scene.from_mesh(path, DARK_GRAY)
    part = scene.parts[0]
    assert len(part.vertices) == 2 + (n_lat - 1) * n_lon and scene.report["watertight"] == [True]

    # A corner's smooth normal averages the faces all round its point. Averaged over faces
    # on one side only (a seam left unwelded) it tilts by about half a grid step; averaged
    # all round, that first-order tilt cancels and what remains (unequal triangles next to
    # the poles, one diagonal per quad) is 0.17 of a step on this grid. A quarter of the
    # grid step (11.25°) separates the two.
    step_deg = 180.0 / n_lat
    smooth_tol_deg = step_deg / 4
    welded = _angle_to_sphere_deg(part)
    assert welded.max() < smooth_tol_deg

    # The same points as separate vertices, as the file stores them: corner_normals groups
    # corners by position, so a part built by hand from the split mesh agrees exactly
    # (the same face normals summed in the same order: 1e-12 is round-off only).
    split = MeshPart(raw.vertices, raw.faces, 0)
    assert len(split.vertices) > len(part.vertices)
    key = np.lexsort(split.vertices[split.faces].reshape(-1, 3).T)
    key_w = np.lexsort(part.vertices[part.faces].reshape(-1, 3).T)
    np.testing.assert_allclose(corner_normals(split).reshape(-1, 3)[key],
                               corner_normals(part).reshape(-1, 3)[key_w], atol=1e-12)

    # ... while corners grouped by vertex index (the duplicates nudged 1e-9 apart, so no
    # position is shared) tilt beyond the tolerance at the seam and the poles
    v = np.array(raw.vertices)
    _, first = np.unique(v, axis=0, return_index=True)
    dup = np.ones(len(v), dtype=bool)
    dup[first] = False
    v[dup] *= 1 + 1e-9
    by_index = _angle_to_sphere_deg(MeshPart(v, raw.faces, 0))
    assert by_index.max() > 2 * smooth_tol_deg
    assert np.count_nonzero(by_index > smooth_tol_deg) >= 2 * n_lon


def test_corner_normals_keep_creases_across_split_vertices():
    # a box whose 8 corners are split into 24 vertices (one per face side, as flat-shaded
    # files store them): the crease test still keeps every face flat
    box = _box()
    tri = box.vertices[box.faces].reshape(-1, 3)
    split = MeshPart(tri, np.arange(len(tri)).reshape(-1, 3), 0)
    fn, _ = split.face_normals_areas()
    np.testing.assert_allclose(corner_normals(split), np.repeat(fn[:, None], 3, axis=1),
                               atol=1e-15)
    # with a crease angle above 90° every face at a corner's point blends in: the
    # area-weighted mean of the normals of the triangles that touch that point
    point = tri.round(12)
    expected = np.empty((len(tri), 3))
    _, area = split.face_normals_areas()
    for k, p in enumerate(point):
        touching = np.any(np.all(point.reshape(-1, 3, 3) == p, axis=-1), axis=1)
        s = (area[touching, None] * fn[touching]).sum(axis=0)
        expected[k] = s / np.linalg.norm(s)
    np.testing.assert_allclose(corner_normals(split, crease_deg=100.0).reshape(-1, 3),
                               expected, atol=1e-14)


@pytest.mark.parametrize("size, offset", [(1e-9, 3e-9), (1.0, 1e12), (BOX, 0.0)],
                         ids=["nanometre box", "box 1e12 from the origin", "plain box"])
def test_welding_is_relative_to_the_mesh_size(tmp_path, size, offset):
    # each triangle with its own three corners (as STL stores them), positions in full
    # precision: welding must find the 8 corners at any scale and any offset
    box = trimesh.creation.box(extents=(size, size, size))
    tri = box.vertices[box.faces].reshape(-1, 3) + [offset, 0.0, 0.0]
    path = tmp_path / "box.obj"
    path.write_text("".join(f"v {float(x)!r} {float(y)!r} {float(z)!r}\n" for x, y, z in tri)
                    + "".join(f"f {3 * k + 1} {3 * k + 2} {3 * k + 3}\n"
                              for k in range(len(box.faces))))
    scene = ml.Scene.from_mesh(path, DARK_GRAY)
    part = scene.parts[0]
    assert len(part.vertices) == 8 and scene.report["faces"] == 12
    assert scene.report["watertight"] == [True] and scene.report["degenerate_faces"] == 0
    # corners a half-edge from the centre: (offset ± size/2) rounds to float64, so the
    # area is exact to the round-off of the offset, 2⁻⁵² relative to it, per coordinate
    area_rtol = 4 * 2.0**-52 * (1 + offset / size)
    assert _area(scene) == pytest.approx(6 * size * size, rel=area_rtol)


def test_recomputed_positions_weld_into_one_point():
    # the same corner written several times with round-off in its last bits (a seam or a
    # pole whose position was recomputed: sin 2π ≈ -2.4e-16, not 0) is one point
    box = _box()
    tri = box.vertices[box.faces].reshape(-1, 3)
    ulps = np.random.default_rng(3).integers(-4, 5, size=tri.shape)
    noisy = tri + ulps * np.spacing(np.abs(tri) + BOX)
    assert len(np.unique(noisy, axis=0)) > 8
    loaded = ml.meshes.load_parts(trimesh.Trimesh(noisy, np.arange(len(tri)).reshape(-1, 3),
                                                process=False))
    (_, mesh), = loaded
    assert len(mesh.vertices) == 8 and trimesh.Trimesh(*mesh).is_watertight


def _two_primitive_gltf(path):
    """A glTF whose one node holds a mesh of two primitives: trimesh loads them as two
    nodes, naming the second with a random suffix."""
    import base64

    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1]],
                   np.float32)
    idx = np.array([0, 1, 2], np.uint16)
    blob = pos.tobytes() + idx.tobytes() + b"\x00\x00"
    uri = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
    views = [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
             {"buffer": 0, "byteOffset": 36, "byteLength": 36},
             {"buffer": 0, "byteOffset": 72, "byteLength": 6}]
    acc = [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
            "min": [0, 0, 0], "max": [1, 1, 0]},
           {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3",
            "min": [0, 0, 1], "max": [1, 1, 1]},
           {"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"}]
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
           "nodes": [{"name": "hull", "mesh": 0}],
           "meshes": [{"name": "hull", "primitives": [{"attributes": {"POSITION": 0},
                                                       "indices": 2},
                                                      {"attributes": {"POSITION": 1},
                                                       "indices": 2}]}],
           "buffers": [{"byteLength": len(blob), "uri": uri}], "bufferViews": views,
           "accessors": acc}
    path.write_text(json.dumps(doc))


def test_part_names_are_the_same_on_every_load(tmp_path):
    # trimesh names the second primitive's node with a random suffix ('hull_3fa2c1'): part
    # names must not change between loads, or --coating PART=... cannot be repeated
    path = tmp_path / "two.gltf"
    _two_primitive_gltf(path)
    names = [[p.name for p in ml.Scene.from_mesh(path, DARK_GRAY).parts] for _ in range(3)]
    assert names[0] == names[1] == names[2] and len(names[0]) == 2
    assert len(set(names[0])) == 2
    from meshladar.meshes.formats import _part_name

    assert _part_name("0_33d0cd", "Truck_1", set()) == "Truck_1"
    assert _part_name("geometry_06ec728accc3a", "geometry_1", set()) == "geometry_1"
    assert _part_name("body", "geometry_0", set()) == "body"
    assert _part_name("0_33d0cd", "Truck", {"Truck", "Truck#2"}) == "Truck#3"


@pytest.mark.parametrize("header", [b"", b"solid box exported as binary"])
def test_a_binary_stl_is_read_as_trimesh_reads_it(tmp_path, header):
    """A binary STL (the CAD tools' format; also one whose header starts with "solid", as
    many exporters write) read without trimesh gives trimesh's own reading of the file,
    welded: the same vertices and faces bit for bit, on a 2,562-vertex sphere moved far
    from the origin in millimetres; a file whose size does not match its count is left to
    trimesh (and named as not a readable STL)."""
    ball = trimesh.creation.icosphere(4, radius=25.0)
    ball.apply_translation([1.5e5, -2.0e4, 3.0e3])
    data = bytearray(ball.export(file_type="stl"))
    data[:len(header)] = header
    path = tmp_path / "ball.stl"
    path.write_bytes(bytes(data))
    (name, mesh), = ml.meshes.load_parts(path)
    ref = trimesh.load(path, file_type="stl", process=False)
    (_, welded), = ml.meshes.load_parts(trimesh.Trimesh(ref.vertices, ref.faces,
                                                        process=False))
    assert name == "mesh" and isinstance(mesh, ml.meshes.TriangleMesh)
    assert len(mesh.vertices) == 2562 and len(mesh.faces) == 5120
    np.testing.assert_array_equal(mesh.vertices, welded.vertices)
    np.testing.assert_array_equal(mesh.faces, welded.faces)
    (_, again), = ml.meshes.load_parts(mesh)             # its own output taken back
    np.testing.assert_array_equal(again.vertices, mesh.vertices)
    assert ml.Scene.from_mesh(mesh, DARK_GRAY).report["faces"] == 5120
    (tmp_path / "cut.stl").write_bytes(bytes(data[:-10]))
    with pytest.raises(GeometryError, match=r"cut\.stl: not a readable STL file"):
        ml.meshes.load_parts(tmp_path / "cut.stl")
