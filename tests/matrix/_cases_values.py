"""The bad-input matrix, the API's values: BRDFs (Sandford-Robertson, the coating
helpers, the other built-in models and a user's own), shapes and scenes (mesh parts, mesh
files and trimesh objects, tessellation) and the ladar."""

from __future__ import annotations

import math
from functools import cache

# meshladar (``ml``) as _matrix imported it: the --before checkout's, if one is given
from _matrix import (COUNTS, DIR, DISK_SPEC, JUNK, NOT_UTF8_OBJ, SCALARS, _EDGES, _al, _box,
                     _dg, _disk, _file_cases, _finite, _lad, _sphere, _sr, _stl, _trimesh,
                     _truncated_stl, api, inf, ml, nan, np, scalar_cases)

# ------------------------------------------------------------------ BRDF
for _p in ("rho_d", "epsilon", "b", "e"):
    scalar_cases("SR", lambda v, p=_p: _sr(**{p: v}), _p, ok=() if _p == "e" else ("zero",),
                 names=(f"{_p} must",),
                 checks={"zero": lambda m, p=_p: getattr(m, p) == 0.0})
api("SR.e=1e-12", lambda: _sr(e=1e-12), "ok")
api("SR.e=1e-13", lambda: _sr(e=1e-13), "error", "e must")
api("SR.e=np.float64", lambda: _sr(e=np.float64(0.2)), "ok", check=lambda m: m.e == 0.2)
api("SR.rho_d=np.int64", lambda: _sr(rho_d=np.int64(0)), "ok")
api("SR.lobes=x", lambda: _sr(lobes="x"), "error", "lobes")
api("SR.lobes=None", lambda: _sr(lobes=None), "error", "lobes")
api("SR.lobes=3", lambda: _sr(lobes=3), "error", "lobes")
api("SR.lobes=BOTH", lambda: _sr(lobes="BOTH"), "error", "lobes")
api("SR.name=3", lambda: _sr(name=3), "error", "name")
api("SR.not-energy-conserving", lambda: _sr(rho_d=0.5, epsilon=0.9), "error",
    ("rho_d", "energy"))
api("SR.diffuse-b0.99-warns", lambda: ml.SandfordRobertson(1.0, 0.0, 0.99, 1.0,
                                                           lobes="diffuse"), "warn")
api("SR.specular-only", lambda: ml.SandfordRobertson(0.0, 0.0, 0.0, 0.007, lobes="specular"),
    "ok")

_THETA = {"nan": nan, "inf": inf, "-inf": -inf, "neg": -0.3, "zero": 0.0, "huge": 1e300,
          "str": "x", "none": None, "ragged": [[0.1], [0.2, 0.3]], "list": [0.1, 0.2],
          "nan-in-list": [0.1, nan], "empty": []}
scalar_cases("SR.monostatic", lambda v: _dg().monostatic(v), "theta", _THETA,
             ok=("neg", "zero", "huge", "list", "empty"),
             checks={"neg": lambda f: f == _dg().monostatic(0.3), "huge": _finite,
                     "list": lambda f: np.shape(f) == (2,), "empty": lambda f: np.size(f) == 0})
api("SR.monostatic.projected=no", lambda: _dg().monostatic(0.1, projected="no"), "error",
    "projected")
api("SR.monostatic.projected=None", lambda: _dg().monostatic(0.1, projected=None), "error",
    "projected")
api("SR.monostatic.90deg-projected", lambda: _al().monostatic(np.pi / 2, projected=True),
    "ok", check=lambda f: math.isfinite(f) and f > 0)
for _fn in ("specular_reflectance", "diffuse_reflectance", "emissivity"):
    api(f"SR.{_fn}(nan)", lambda f=_fn: getattr(_dg(), f)(nan), "error", "theta")
    api(f"SR.{_fn}(str)", lambda f=_fn: getattr(_dg(), f)("x"), "error", "theta")

_VEC = {"nan": (nan, 0, 1), "zero": (0, 0, 0), "short": (0, 1), "str": "x", "none": None,
        "inf": (0, inf, 1), "ragged": [[0, 0, 1], [0, 1]]}
for _arg, _pos in (("incident", 0), ("reflected", 1), ("normal", 2)):
    for _key, _v in _VEC.items():
        def _call(v=_v, pos=_pos):
            args = [(0, 0, 1), (0, 0.2, 1), (0, 0, 1)]
            args[pos] = v
            return _dg().evaluate(*args)
        api(f"SR.evaluate.{_arg}={_key}", _call, "error", _arg)
api("SR.evaluate.shapes", lambda: _dg().evaluate(np.ones((2, 3)), np.ones((3, 3)),
                                                 np.ones((3, 3))), "error", "broadcast")
api("SR.evaluate.projected=x", lambda: _dg().evaluate((0, 0, 1), (0, 0, 1), projected="x"),
    "error", "projected")
api("SR.evaluate.opposite", lambda: _dg().evaluate((1, 0, 0), (-1, 0, 0)), "ok",
    check=_finite)
api("SR.evaluate_angles.theta_i=nan", lambda: _dg().evaluate_angles(nan, 0.1), "error",
    "theta_i")
api("SR.evaluate_angles.theta_r=inf", lambda: _dg().evaluate_angles(0.1, inf), "error",
    "theta_r")
api("SR.evaluate_angles.delta_phi=str", lambda: _dg().evaluate_angles(0.1, 0.1, "x"),
    "error", "delta_phi")
api("SR.evaluate_angles.delta_phi=None", lambda: _dg().evaluate_angles(0.1, 0.1, None),
    "error", "delta_phi")
api("SR.evaluate_angles.mirror", lambda: _al().evaluate_angles(0.3, 0.3, np.pi), "ok",
    check=lambda f: f > 1.0)

# ------------------------------------------------------------------ coating helpers
for _key, _v in {"nan": nan, "neg": -0.1, "above-1": 2.0, "str": "x", "none": None}.items():
    api(f"materials.lambertian.rho_d={_key}", lambda v=_v: ml.materials.lambertian(v),
        "error", "rho_d")
    api(f"materials.glint.rho_s={_key}", lambda v=_v: ml.materials.glint(0.1, rho_s=v),
        "error", "rho_s")
for _key, _v in {"nan": nan, "zero": 0.0, "neg": -0.1, "above-1": 2.0, "str": "x"}.items():
    api(f"materials.glint.e={_key}", lambda v=_v: ml.materials.glint(v), "error", "e must")
api("materials.lambertian.rho_d=0", lambda: ml.materials.lambertian(0.0), "ok",
    check=lambda m: m.monostatic(0.0) == 0.0)

# ------------------------------------------------------------------ the BRDF protocol: the
# other built-in models, and a user's own


def _brdf(model, *args, **kw):
    return getattr(ml.brdf, model)(*args, **kw)


scalar_cases("Lambertian", lambda v: _brdf("Lambertian", v), "albedo", ok=("zero",),
             checks={"zero": lambda m: m.monostatic(0.0) == 0.0})
for _p, _i in (("kd", 0), ("ks", 1)):
    for _key in ("nan", "neg", "huge", "str", "none"):
        def _phong(v=SCALARS[_key], i=_i):
            args = [0.3, 0.3, 10.0]
            args[i] = v
            return _brdf("Phong", *args)
        api(f"Phong.{_p}={_key}", _phong, "error", _p)
for _key, _v in {"nan": nan, "neg": -1.0, "huge": 1e300, "str": "x", "inf": inf}.items():
    api(f"Phong.exponent={_key}", lambda v=_v: _brdf("Phong", 0.3, 0.3, v), "error", "exponent")
api("Phong.exponent=0", lambda: _brdf("Phong", 0.3, 0.3, 0.0), "ok",
    check=lambda m: m.monostatic(0.0) > 0)
api("Phong.not-energy-conserving", lambda: _brdf("Phong", 0.7, 0.7, 10.0), "error",
    ("kd + ks",))
for _key, _v in {"zero": 0.0, "tiny": 1e-5, "nan": nan, "above-1": 2.0, "str": "x",
                 "none": None}.items():
    api(f"GGX.alpha={_key}", lambda v=_v: _brdf("GGX", v), "error", "alpha")
for _key, _v in {"neg": -0.1, "above-1": 2.0, "nan": nan, "none": None}.items():
    api(f"GGX.reflectance={_key}", lambda v=_v: _brdf("GGX", 0.3, v), "error", "reflectance")
api("GGX.grazing", lambda: _brdf("GGX", 1e-4).monostatic(np.pi / 2, projected=True), "ok",
    check=lambda f: math.isfinite(f))
for _key, _t, _v in (("theta-from-10", [10, 90], [1, 1]), ("theta-to-80", [0, 80], [1, 1]),
                     ("theta-decreasing", [0, 60, 30, 90], [1, 1, 1, 1]),
                     ("theta-one", [0], [1]), ("theta-nan", [0, nan, 90], [1, 1, 1]),
                     ("theta-str", "x", [1, 1]), ("theta-2d", [[0, 90]], [[1, 1]])):
    api(f"Tabulated.{_key}", lambda t=_t, v=_v: _brdf("Tabulated", t, v), "error", "theta_deg")
for _key, _v in (("negative", [1, -1]), ("nan", [1, nan]), ("short", [1]), ("str", "x"),
                 ("inf", [inf, 1])):
    api(f"Tabulated.values-{_key}", lambda v=_v: _brdf("Tabulated", [0, 90], v), "error",
        "values")
api("Tabulated.projected_values=yes", lambda: _brdf("Tabulated", [0, 90], [1, 1],
                                                    projected_values="yes"),
    "error", "projected_values")
api("Tabulated.bistatic", lambda: ml.simulate(ml.Scene.from_parts(
    [ml.meshes.sphere((0, 0, 0), 0.5, 0, subdivisions=2)], [_brdf("Tabulated", [0, 90], [1, 1])]),
    _lad(), model="mesh", receiver=(0, 1, 1)), "error", ("bistatic", "receiver"))
for _model, _args in (("Lambertian", (0.5,)), ("Phong", (0.3, 0.3, 10.0)), ("GGX", (0.3,)),
                      ("Tabulated", ([0, 90], [1, 1]))):
    api(f"{_model}.name=3", lambda m=_model, a=_args: _brdf(m, *a, name=3), "error", "name")
    api(f"{_model}.analytic", lambda m=_model, a=_args: ml.simulate(
        ml.Scene([ml.Disk((0, 0), 0.5, _brdf(m, *a))]), _lad()), "ok",
        check=lambda s: _finite(s) and s.values.sum() > 0)
api("Disk.material=class", lambda: ml.Disk((0, 0), 0.5, ml.brdf.Lambertian), "error",
    "material")


@cache
def _user_brdfs():
    """A user's models that break the protocol: NaN, negative, wrong shape, no projected."""
    class NaNModel(ml.brdf.BRDF):
        def projected(self, cos_theta, sin_theta):
            return np.full(np.shape(cos_theta), nan)

    class NegativeModel(ml.brdf.BRDF):
        def projected(self, cos_theta, sin_theta):
            return -np.ones(np.shape(cos_theta))

    class ShapeModel(ml.brdf.BRDF):
        def projected(self, cos_theta, sin_theta):
            return np.ones(3)

    class NoProjectedModel(ml.brdf.BRDF):
        pass

    return {"nan": NaNModel(), "negative": NegativeModel(), "shape": ShapeModel(),
            "no-projected": NoProjectedModel()}


for _key, _name in (("nan", "NaNModel"), ("negative", "NegativeModel"),
                    ("shape", "ShapeModel"), ("no-projected", "NoProjectedModel")):
    api(f"user-BRDF.{_key}.monostatic", lambda k=_key: _user_brdfs()[k].monostatic(0.1),
        "error", _name)
    api(f"user-BRDF.{_key}.analytic", lambda k=_key: ml.simulate(
        ml.Scene([ml.Disk((0, 0), 0.5, _user_brdfs()[k])]), _lad()), "error", _name)
    api(f"user-BRDF.{_key}.mesh", lambda k=_key: ml.simulate(ml.Scene.from_parts(
        [ml.meshes.sphere((0, 0, 0), 0.5, 0, subdivisions=2)], [_user_brdfs()[k]]), _lad(),
        model="mesh"), "error", _name)

# ------------------------------------------------------------------ shapes and scenes
_CENTERS = {"nan": (nan, 0.0), "inf": (inf, 0.0), "short": (0.0,), "long": (0, 0, 0),
            "str": "ab", "none": None, "nested": [[0, 0]]}
for _key, _v in _CENTERS.items():
    api(f"Disk.center={_key}", lambda v=_v: ml.Disk(v, 0.5, _dg()), "error", "center")
    api(f"Ellipse.center={_key}", lambda v=_v: ml.Ellipse(v, (0.5, 0.3), 0.0, _dg()), "error",
        "center")
scalar_cases("Disk", lambda v: ml.Disk((0.0, 0.0), v, _dg()), "radius", ok=("huge",))
api("Disk.material=str", lambda: ml.Disk((0, 0), 0.5, "dark_gray"), "error", "material")
api("Disk.material=None", lambda: ml.Disk((0, 0), 0.5, None), "error", "material")
api("Disk.name=3", lambda: ml.Disk((0, 0), 0.5, _dg(), name=3), "error", "name")
for _key, _v in {"nan": (nan, 0.3), "inf": (0.5, inf), "short": (0.5,), "neg": (0.5, -0.3),
                 "zero": (0.0, 0.3), "str": "ab", "none": None,
                 "three": (0.5, 0.3, 0.1)}.items():
    api(f"Ellipse.semi_axes={_key}", lambda v=_v: ml.Ellipse((0, 0), v, 0.0, _dg()), "error",
        "semi_axes")
scalar_cases("Ellipse", lambda v: ml.Ellipse((0, 0), (0.5, 0.3), v, _dg()), "angle_deg",
             ok=("neg", "zero", "huge"))
api("Ellipse.material=str", lambda: ml.Ellipse((0, 0), (0.5, 0.3), 0.0, "x"), "error",
    "material")

api("Scene.shapes=[]", lambda: ml.Scene([]), "error", "shapes")
api("Scene.shapes=None", lambda: ml.Scene(None), "error", "shapes")
api("Scene.shapes=5", lambda: ml.Scene(5), "error", "shapes")
api("Scene.shapes=[str]", lambda: ml.Scene(["disk"]), "error", "shapes[0]")
api("Scene.shapes=Disk", lambda: ml.Scene(ml.Disk((0, 0), 0.5, _dg())), "error", "shapes")
api("Scene.overlap", lambda: ml.Scene([ml.Disk((0, 0), 0.5, _dg()),
                                       ml.Disk((0.5, 0), 0.5, _dg())]), "error", "overlap")
api("Scene.overlap-ellipses", lambda: ml.Scene([
    ml.Ellipse((0, 0), (0.6, 0.2), 0.0, _dg()), ml.Ellipse((0, 0), (0.6, 0.2), 90.0, _dg())]),
    "error", "overlap")
api("Scene.same-disk-twice", lambda: ml.Scene([ml.Disk((0, 0), 0.5, _dg())] * 2), "error",
    "overlap")
api("Scene.touching", lambda: ml.Scene([ml.Disk((-0.3, 0), 0.4, _dg()),
                                        ml.Disk((0.4, 0), 0.3, _al())]), "ok",
    check=lambda s: len(s) == 2)
api("Scene.generator", lambda: ml.Scene(ml.Disk((x, 0), 0.1, _dg()) for x in (0, 1)), "ok",
    check=lambda s: len(s) == 2)


def _part(vertices=((0, 0, 0), (1, 0, 0), (0, 1, 0)), faces=((0, 1, 2),), material=0):
    return ml.meshes.MeshPart(np.array(vertices, dtype=float), np.array(faces), material)


api("Scene.from_parts.materials=[]", lambda: ml.Scene.from_parts([_part()], []), "error",
    "material")
api("Scene.from_parts.materials=[str]", lambda: ml.Scene.from_parts([_part()], ["x"]),
    "error", "materials[0]")
api("Scene.from_parts.materials=str", lambda: ml.Scene.from_parts([_part()], "dark_gray"),
    "error", "materials")
api("Scene.from_parts.parts=[]", lambda: ml.Scene.from_parts([], [_dg()]), "error",
    ("parts", "faces"))
api("Scene.from_parts.parts=[str]", lambda: ml.Scene.from_parts(["x"], [_dg()]), "error",
    "parts")
api("Scene.from_parts.index=1", lambda: ml.Scene.from_parts([_part(material=1)], [_dg()]),
    "error", "material")
api("MeshPart.vertices=nan", lambda: _part(vertices=((nan, 0, 0), (1, 0, 0), (0, 1, 0))),
    "error", "vertices")
api("MeshPart.vertices=2d", lambda: _part(vertices=((0, 0), (1, 0), (0, 1))), "error",
    "vertices")
api("MeshPart.faces=float", lambda: _part(faces=((0.0, 1.0, 2.5),)), "error", "faces")
api("MeshPart.faces=out-of-range", lambda: _part(faces=((0, 1, 3),)), "error", "faces")
api("MeshPart.faces=negative", lambda: _part(faces=((0, 1, -1),)), "error", "faces")
api("Scene.from_parts.degenerate-only", lambda: ml.Scene.from_parts(
    [_part(vertices=((0, 0, 0), (1, 0, 0), (2, 0, 0)))], [_dg()]), "error", "faces")
api("Scene.from_parts.inverted-warns", lambda: ml.Scene.from_parts(
    [ml.meshes.MeshPart(_sphere().parts[0].vertices, _sphere().parts[0].faces[:, ::-1], 0)],
    [_dg()]), "warn")

# mesh files and trimesh objects
_file_cases("Scene.from_mesh.stl", "api", lambda p: ml.Scene.from_mesh(p, _dg()), ".stl",
            {"missing": None, "dir": DIR, "empty": b"", "whitespace": b"  \n\t\n",
             "junk": JUNK, "truncated": _truncated_stl}, ("bad.stl",))
_file_cases("Scene.from_mesh.obj", "api", lambda p: ml.Scene.from_mesh(p, _dg()), ".obj",
            {"junk": JUNK, "not-utf8": NOT_UTF8_OBJ, "text": b"hello world\n"}, ("bad.obj",))
_file_cases("Scene.from_mesh.ply", "api", lambda p: ml.Scene.from_mesh(p, _dg()), ".ply",
            {"point-cloud": b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                            b"property float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n"
                            b"0 1 0\n"}, ("bad.ply",))
_file_cases("Scene.from_mesh.toml", "api", lambda p: ml.Scene.from_mesh(p, _dg()), ".toml",
            {"spec": DISK_SPEC}, ("bad.toml",))
_file_cases("Scene.from_mesh.dat", "api", lambda p: ml.Scene.from_mesh(p, _dg()), ".dat",
            {"binary-stl": _stl}, (), expect="ok")
api("Scene.from_mesh.None", lambda: ml.Scene.from_mesh(None, _dg()), "error", "mesh")
api("Scene.from_mesh.int", lambda: ml.Scene.from_mesh(3, _dg()), "error", "mesh")
api("Scene.from_mesh.empty-trimesh", lambda: ml.Scene.from_mesh(_trimesh().Trimesh(), _dg()),
    "error", "mesh")
api("Scene.from_mesh.nan-vertices", lambda: ml.Scene.from_mesh(_trimesh().Trimesh(
    vertices=[[nan, 0, 0], [1, 0, 0], [0, 1, 0]], faces=[[0, 1, 2]], process=False), _dg()),
    "error", "finite")
api("Scene.from_mesh.no-faces", lambda: ml.Scene.from_mesh(_trimesh().Trimesh(
    vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], faces=np.zeros((0, 3), int)), _dg()),
    "error", ("faces", "point"))
api("Scene.from_mesh.point-cloud", lambda: ml.Scene.from_mesh(
    _trimesh().PointCloud([[0, 0, 0], [1, 0, 0]]), _dg()), "error", "point")
api("Scene.from_mesh.empty-scene", lambda: ml.Scene.from_mesh(_trimesh().Scene(), _dg()),
    "error", "mesh")

api("Scene.from_mesh.material=None", lambda: _box(), "error", "material")
api("Scene.from_mesh.material=str", lambda: _box(material="dark_gray"), "error", "material")
api("Scene.from_mesh.materials=unknown-part", lambda: _box(material=_dg(),
                                                           materials={"nope": _al()}),
    "error", "nope")
api("Scene.from_mesh.materials=list", lambda: _box(material=_dg(), materials=[_al()]),
    "error", "materials")
api("Scene.from_mesh.transform=nan", lambda: _box(material=_dg(),
                                                  transform=np.full((4, 4), nan)),
    "error", "transform")
api("Scene.from_mesh.transform=3x3", lambda: _box(material=_dg(), transform=np.eye(3)),
    "error", "transform")
api("Scene.from_mesh.transform=singular", lambda: _box(material=_dg(),
                                                       transform=np.zeros((4, 4))),
    "error", ("transform", "faces"))
api("Scene.from_mesh.face_materials=short", lambda: _box(materials=[_dg()],
                                                         face_materials=[0, 0]),
    "error", "face_materials")
api("Scene.from_mesh.face_materials=index", lambda: _box(materials=[_dg()],
                                                         face_materials=[1] * 12),
    "error", ("material", "face_materials"))
api("Scene.from_mesh.face_materials-without-list", lambda: _box(
    material=_dg(), face_materials=[0] * 12), "error", "materials")
api("Scene.from_mesh.box", lambda: _box(material=_dg()), "ok",
    check=lambda s: s.report["faces"] == 12)

for _key, _v in {"2": 2, "zero": 0, "neg": -1, "float": 1.5, "str": "x", "none": None,
                 "bool": True, "huge": 10**8}.items():
    api(f"Scene.tessellate.segments={_key}", lambda v=_v: _disk().tessellate(v), "error",
        "segments")
api("Scene.tessellate.segments=3", lambda: _disk().tessellate(3), "ok",
    check=lambda s: s.is_mesh)
for _key, _v in {"nan": nan, "zero": 0.0, "neg": -1.0, "str": "x", "inf": inf}.items():
    api(f"Scene.tessellate.height={_key}", lambda v=_v: _disk().tessellate(8, height=v),
        "error", "height")
for _key, _v in {"nan": nan, "str": "x", "none": None}.items():
    api(f"Scene.tessellate.z0={_key}", lambda v=_v: _disk().tessellate(8, z0=v), "error", "z0")
api("Scene.tessellate.of-mesh", lambda: _sphere().tessellate(8), "error", "tessellate")

# ------------------------------------------------------------------ the ladar
for _key, _v in {"nan": [0.0, nan], "inf": [inf], "empty": [], "none": None, "str": "x",
                 "2d": [[0.0, 90.0]], "scalar": 5.0, "ragged": [[0.0], [1.0, 2.0]]}.items():
    api(f"Ladar.angles_deg={_key}", lambda v=_v: ml.Ladar(v, _EDGES), "error", "angles_deg")
api("Ladar.angles_deg=huge", lambda: ml.Ladar([1e300], _EDGES), "ok")
api("Ladar.angles_deg=negative", lambda: ml.Ladar([-90.0, 720.0], _EDGES), "ok",
    check=lambda lad: lad.n_views == 2)
for _key, _v in {"nan": [0.0, nan], "decreasing": [1.0, 0.0], "one": [0.0],
                 "repeated": [0.0, 0.0, 1.0], "none": None, "str": "x", "2d": [[0.0, 1.0]],
                 "infinite": [-inf, inf], "empty": []}.items():
    api(f"Ladar.bin_edges={_key}", lambda v=_v: ml.Ladar([0.0], v), "error", "bin_edges")
api("Ladar.bin_edges=huge", lambda: ml.Ladar([0.0], [-1e300, 1e300]), "ok")
for _key, _v in {"zero": [[0, 0, 0]], "nan": [[nan, 0, 1]], "1d": [0, 0, 1],
                 "2-wide": [[1, 0]], "empty": np.zeros((0, 3)), "str": "x"}.items():
    api(f"Ladar.view_vectors={_key}", lambda v=_v: ml.Ladar(None, _EDGES, view_vectors=v),
        "error", "view_vectors")
api("Ladar.view_vectors+angles-lengths", lambda: ml.Ladar([0.0, 1.0], _EDGES,
                                                          view_vectors=[[1, 0, 0]]),
    "error", ("angles_deg", "view_vectors"))
api("Ladar.view_vectors+angles-disagree", lambda: ml.Ladar([90.0], _EDGES,
                                                           view_vectors=[[1, 0, 0]]),
    "error", ("angles_deg", "view_vectors"))
api("Ladar.view_vectors=pole", lambda: ml.Ladar(None, _EDGES, view_vectors=[[0, 0, 1]]), "ok",
    check=lambda lad: not lad.planar)
api("Ladar.huge-sinogram", lambda: ml.Ladar(np.arange(10**6), np.linspace(-1, 1, 10**4)),
    "error", "ladar")

for _key, _v in COUNTS.items():
    api(f"Ladar.centered.n_bins={_key}", lambda v=_v: ml.Ladar.centered(v, 0.1), "error",
        "n_bins")
api("Ladar.centered.n_bins=1", lambda: ml.Ladar.centered(1, 0.1), "ok",
    check=lambda lad: lad.n_bins == 1)
# bins wider than scenes meshladar takes (1e30 across) are refused (issue 29: overflowed)
scalar_cases("Ladar.centered", lambda v: ml.Ladar.centered(8, v), "bin_width")
scalar_cases("Ladar.centered", lambda v: ml.Ladar.centered(8, 0.1, center=v), "center",
             ok=("neg", "zero"), names=("center", "bin_edges"))
api("Ladar.centered.angles_deg=[]", lambda: ml.Ladar.centered(8, 0.1, angles_deg=[]), "error",
    "angles_deg")
api("Ladar.centered.angles_deg=nan", lambda: ml.Ladar.centered(8, 0.1, angles_deg=[nan]),
    "error", "angles_deg")
scalar_cases("Ladar.paper", lambda v: ml.Ladar.paper(v), "radius")
api("Ladar.paper.n_bins=0", lambda: ml.Ladar.paper(n_bins=0), "error", "n_bins")

api("Ladar.covering.neither", lambda: ml.Ladar.covering(_disk()), "error",
    ("bin_width", "n_bins"))
for _key, _v in {"nan": nan, "zero": 0.0, "neg": -1.0, "str": "x", "tiny": 1e-12,
                 "inf": inf}.items():
    api(f"Ladar.covering.bin_width={_key}", lambda v=_v: ml.Ladar.covering(_disk(),
                                                                           bin_width=v),
        "error", "bin_width")
api("Ladar.covering.bin_width=huge", lambda: ml.Ladar.covering(_disk(), bin_width=1e300),
    "ok", check=lambda lad: lad.n_bins == 1)
for _key, _v in {"zero": 0, "float": 1.5, "str": "x", "huge": 10**10}.items():
    api(f"Ladar.covering.n_bins={_key}", lambda v=_v: ml.Ladar.covering(_disk(), n_bins=v),
        "error", "n_bins")
for _key, _v in {"neg": -1.0, "nan": nan, "str": "x", "inf": inf}.items():
    api(f"Ladar.covering.margin={_key}", lambda v=_v: ml.Ladar.covering(_disk(), n_bins=8,
                                                                        margin=v),
        "error", "margin")
api("Ladar.covering.scene=str", lambda: ml.Ladar.covering("disk", n_bins=8), "error", "scene")
api("Ladar.covering.scene=None", lambda: ml.Ladar.covering(None, n_bins=8), "error", "scene")
api("Ladar.covering.angles_deg=[]", lambda: ml.Ladar.covering(_disk(), n_bins=8,
                                                              angles_deg=[]),
    "error", "angles_deg")
api("Ladar.covering.view_vectors=zero", lambda: ml.Ladar.covering(
    _sphere(), n_bins=8, view_vectors=[[0, 0, 0]]), "error", "view_vectors")
api("Ladar.covering.one-bin-mesh", lambda: ml.Ladar.covering(_sphere(), n_bins=1), "ok",
    check=lambda lad: lad.n_bins == 1)
api("Ladar.covering.off-axis-warns", lambda: ml.Ladar.covering(ml.Scene.from_parts(
    [ml.meshes.sphere((100, 0, 0), 0.5, 0, subdivisions=1)], [_dg()]), n_bins=8), "warn")
