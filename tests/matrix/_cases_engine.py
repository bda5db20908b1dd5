"""The bad-input matrix, the API's engine: simulate (every model and option), trace and
weigh, sinograms, reconstruction, result files, coating tables, phantom specs, the studies
(refused before any work is done) and the viewer (off screen)."""

from __future__ import annotations

# meshladar (``ml``) as _matrix imported it: the --before checkout's, if one is given
from _matrix import (BAD_TOML, COUNTS, DIR, DISK_SPEC, JUNK, LONG_INT_TOML, NOT_UTF8_TOML,
                     TABLE, _EDGES, _al, _box, _deep_meta_result, _dg, _disk, _file_cases,
                     _finite, _hits, _image_result, _lad, _no_meta_result, _pickled_result,
                     _read_only, _refuses_many_jobs, _result, _sino, _spec, _sphere,
                     _truncated_result, api, files, inf, ml, nan, np, scalar_cases)

# ------------------------------------------------------------------ simulate


def _mesh_sim(**kw):
    return ml.simulate(_sphere(), _lad(), model="mesh", **kw)


def _pixel_sim(**kw):
    return ml.simulate(_disk(), _lad(), model="pixel", **kw)


api("simulate.scene=str", lambda: ml.simulate("disk", _lad()), "error", "scene")
api("simulate.scene=None", lambda: ml.simulate(None, _lad()), "error", "scene")
api("simulate.ladar=str", lambda: ml.simulate(_disk(), "ladar"), "error", "ladar")
api("simulate.ladar=None", lambda: ml.simulate(_disk(), None), "error", "ladar")
for _key, _v in {"x": "x", "none": None, "int": 3, "upper": "MESH"}.items():
    api(f"simulate.model={_key}", lambda v=_v: ml.simulate(_disk(), _lad(), model=v), "error",
        "model")
api("simulate.unknown-option", lambda: _mesh_sim(bogus=1), "error", "bogus")
api("simulate.radiometry=power", lambda: _mesh_sim(radiometry="power"), "ok",
    check=lambda s: s.info["radiometry"] == "power")
api("simulate.radiometry=watts", lambda: _mesh_sim(radiometry="watts"), "error", "radiometry")
api("simulate.analytic.radiometry=None", lambda: ml.simulate(_disk(), _lad(), radiometry=None),
    "error", "radiometry")
api("simulate.segments", lambda: _mesh_sim(segments=64), "error", "segments")
api("simulate.analytic-of-mesh", lambda: ml.simulate(_sphere(), _lad()), "error", "mesh")
api("simulate.analytic.jobs=0", lambda: ml.simulate(_disk(), _lad(), jobs=0), "error", "jobs")
api("simulate.analytic.progress=str", lambda: ml.simulate(_disk(), _lad(), progress="yes"),
    "error", "progress")
api("simulate.pixel.progress=None", lambda: ml.simulate(_disk(), _lad(), model="pixel",
                                                        progress=None), "error", "progress")
api("simulate.pixel-of-mesh", lambda: ml.simulate(_sphere(), _lad(), model="pixel"), "error",
    "mesh")
api("simulate.analytic.off-plane", lambda: ml.simulate(
    _disk(), ml.Ladar(None, _EDGES, view_vectors=[[0, 0, 1]])), "error", "view")
api("simulate.analytic", lambda: ml.simulate(_disk(), _lad()), "ok",
    check=lambda s: s.shape == (2, 8) and _finite(s) and s.values.sum() > 0)
api("simulate.analytic.bins-miss-warns", lambda: ml.simulate(_disk(), ml.Ladar([0.0],
                                                                               [5.0, 6.0])),
    "warn")
api("simulate.mesh.bins-miss-warns", lambda: ml.simulate(_sphere(), ml.Ladar([0.0],
                                                                             [5.0, 6.0]),
                                                         model="mesh"), "warn")
api("simulate.analytic.huge-disk-warns", lambda: ml.simulate(
    ml.Scene([ml.Disk((0, 0), 1e300, _dg())]), _lad()), "warn")
api("simulate.analytic.huge-disk-covered", lambda: ml.simulate(
    ml.Scene([ml.Disk((0, 0), 1e300, _dg())]), ml.Ladar.covering(
        ml.Scene([ml.Disk((0, 0), 1e300, _dg())]), n_bins=8, angles_deg=[0.0, 90.0])), "ok",
    check=lambda s: _finite(s) and s.values.max() > 0)


def _sized_sphere(radius):
    scene = ml.Scene.from_parts([ml.meshes.sphere((0, 0, 0), radius, 0, subdivisions=2)],
                                [_dg()])
    return ml.simulate(scene, ml.Ladar.covering(scene, n_bins=8, angles_deg=[0.0, 90.0]),
                       model="mesh")


api("simulate.mesh.size=1e40", lambda: _sized_sphere(1e40), "error", "scene")
api("simulate.mesh.size=1e-40", lambda: _sized_sphere(1e-40), "error", "scene")
api("simulate.mesh.size=1e25", lambda: _sized_sphere(1e25), "ok", check=_finite)
api("simulate.pixel", lambda: _pixel_sim(), "ok", check=_finite)
scalar_cases("simulate.pixel", lambda v: _pixel_sim(pixel_size=v), "pixel_size",
             ok=("none",))
api("simulate.pixel.pixel_size=tiny", lambda: _pixel_sim(pixel_size=1e-6), "error",
    "pixel_size")
for _key, _v in {"nan": nan, "zero": 0.0, "neg": -1.0, "tiny": 1e-12, "str": "x"}.items():
    api(f"simulate.pixel.ray_spacing={_key}", lambda v=_v: _pixel_sim(ray_spacing=v), "error",
        "ray_spacing")

api("simulate.mesh", lambda: _mesh_sim(), "ok",
    check=lambda s: s.shape == (2, 8) and _finite(s) and s.values.sum() > 0)
for _key, _v in {"x": "x", "int": 3, "empty": "", "upper": "3D"}.items():
    api(f"simulate.mesh.mode={_key}", lambda v=_v: _mesh_sim(mode=v), "error", "mode")
api("simulate.mesh.mode=slice", lambda: _mesh_sim(mode="slice"), "ok", check=_finite)
for _v in ("optix", "", None, 3):
    api(f"simulate.mesh.backend={_v!r}", lambda v=_v: _mesh_sim(backend=v), "error", "backend")
for _v in ("auto", "packets", "embreex"):
    api(f"simulate.mesh.backend={_v}", lambda v=_v: _mesh_sim(backend=v), "ok", check=_finite)
api("simulate.analytic.backend", lambda: ml.simulate(_disk(), _lad(), backend="packets"),
    "error", "backend")
for _key, _v in {"nan": nan, "inf": inf, "str": "x", "bool": True, "list": [0.0]}.items():
    api(f"simulate.mesh.z0={_key}", lambda v=_v: _mesh_sim(mode="slice", z0=v), "error", "z0")
api("simulate.mesh.z0-with-3d", lambda: _mesh_sim(mode="3d", z0=0.1), "error", "z0")
api("simulate.mesh.z0-outside-warns", lambda: _mesh_sim(mode="slice", z0=5.0), "warn")
scalar_cases("simulate.mesh", lambda v: _mesh_sim(ray_spacing=v), "ray_spacing", ok=("none",))
api("simulate.mesh.ray_spacing=wide", lambda: _mesh_sim(ray_spacing=1e3), "warn")
#   rays wider than the target: all zeros, saying why; 1e300 (above 1e30) is refused by name
api("simulate.mesh.ray_spacing=tiny", lambda: _mesh_sim(ray_spacing=1e-9), "error",
    "ray_spacing")
scalar_cases("simulate.mesh", lambda v: _mesh_sim(rays_per_bin=v), "rays_per_bin",
             ok=("none",), names=("rays_per_bin", "ray_spacing"))
api("simulate.mesh.rays_per_bin=tiny", lambda: _mesh_sim(rays_per_bin=1e-300), "warn")
api("simulate.mesh.ray_spacing+rays_per_bin", lambda: _mesh_sim(ray_spacing=0.1,
                                                                rays_per_bin=2),
    "error", ("ray_spacing", "rays_per_bin"))
for _key, _v in {"x": "x", "int": 3}.items():
    api(f"simulate.mesh.sampling={_key}", lambda v=_v: _mesh_sim(sampling=v), "error",
        "sampling")
api("simulate.mesh.sampling=regular", lambda: _mesh_sim(sampling="regular"), "ok",
    check=_finite)
api("simulate.mesh.regular+seed", lambda: _mesh_sim(sampling="regular", seed=1), "error",
    "seed")
for _key, _v in {"neg": -1, "float": 0.5, "str": "1", "bool": True, "nan": nan,
                 "list": [1, 2]}.items():
    api(f"simulate.mesh.seed={_key}", lambda v=_v: _mesh_sim(seed=v), "error", "seed")
api("simulate.mesh.seed=huge", lambda: _mesh_sim(seed=2**70), "ok", check=_finite)
api("simulate.mesh.seed=np.int64", lambda: _mesh_sim(seed=np.int64(3)), "ok")
for _key, _v in {"x": "x", "int": 3, "upper": "FLAT"}.items():
    api(f"simulate.mesh.normals={_key}", lambda v=_v: _mesh_sim(normals=v), "error", "normals")
api("simulate.mesh.normals=smooth", lambda: _mesh_sim(normals="smooth"), "ok", check=_finite)
api("simulate.mesh.normals=exact", lambda: _mesh_sim(normals="exact"), "ok", check=_finite)
api("simulate.mesh.normals=exact-without", lambda: ml.simulate(
    _box(material=_dg()), _lad(), model="mesh", normals="exact"), "error", "exact")
api("simulate.mesh.back_faces=x", lambda: _mesh_sim(back_faces="x"), "error", "back_faces")
for _key, _v in {"str": "no", "int": 1}.items():
    api(f"simulate.mesh.footprint={_key}", lambda v=_v: _mesh_sim(footprint=v), "error",
        "footprint")
api("simulate.mesh.footprint=True", lambda: _mesh_sim(footprint=True), "ok", check=_finite)
for _key, _v in {"nan": (nan, 0, 0), "zero": (0, 0, 0), "short": (1, 0), "str": "x",
                 "per-view-count": [(0, 1, 0)] * 3, "opposite": (-1, 0, 0),
                 "inf": (inf, 0, 0)}.items():
    api(f"simulate.mesh.receiver={_key}", lambda v=_v: _mesh_sim(receiver=v), "error",
        "receiver")
api("simulate.mesh.receiver+footprint", lambda: _mesh_sim(receiver=(0, 1, 1),
                                                          footprint=True),
    "error", ("footprint", "receiver"))
# the 320-face sphere has lit faces exactly edge-on to (0, 1, 1): under Eq. 8 their F's
# 1/cos θr made bins of 7e9 (against 5e-3) without a word; now it is said, and received
# power is the finite answer
api("simulate.mesh.receiver-edge-on-warns", lambda: _mesh_sim(receiver=(0, 1, 1)), "warn",
    "receiver")
api("simulate.mesh.receiver", lambda: _mesh_sim(receiver=(0, 1, 1), radiometry="power"),
    "ok", check=_finite)
api("simulate.mesh.receiver-oblique", lambda: _mesh_sim(receiver=(0.3, 0.5, 0.81)), "ok",
    check=_finite)
for _key, _v in {"zero": 0.0, "neg": -0.1, "one": 1.0, "above-1": 1.5, "nan": nan,
                 "str": "x", "bool": True}.items():
    api(f"simulate.mesh.tol={_key}", lambda v=_v: _mesh_sim(tol=v), "error", "tol")
api("simulate.mesh.tol+run_dir", lambda tmp: _mesh_sim(tol=0.5, run_dir=tmp / "run"),
    "error", ("tol", "run_dir"))
api("simulate.mesh.tol+ray_spacing", lambda: _mesh_sim(tol=0.5, ray_spacing=0.1), "error",
    ("tol", "ray_spacing"))
for _key, _v in {"zero": 0, "nan": nan, "str": "x", "neg": -5}.items():
    api(f"simulate.mesh.max_rays={_key}", lambda v=_v: _mesh_sim(tol=0.5, max_rays=v),
        "error", "max_rays")
api("simulate.mesh.max_rays-without-tol", lambda: _mesh_sim(max_rays=1e6), "error",
    "max_rays")
api("simulate.mesh.tol-budget-warns", lambda: _mesh_sim(tol=0.01, max_rays=1), "warn",
    check=_finite)

for _key, _v in {"zero": 0, "neg": -1, "float": 2.5, "str": "2", "bool": True,
                 "nan": nan}.items():
    api(f"simulate.mesh.jobs={_key}", lambda v=_v: _mesh_sim(jobs=v), "error", "jobs")
api("simulate.mesh.jobs=huge", lambda: _mesh_sim(jobs=10**5), "error", "jobs",
    precheck=_refuses_many_jobs)
api("simulate.mesh.jobs=1", lambda: _mesh_sim(jobs=1), "ok", check=_finite)
api("simulate.mesh.executor=str", lambda: _mesh_sim(executor="x"), "error", "executor")
api("simulate.mesh.executor=object", lambda: _mesh_sim(executor=object()), "error",
    "executor")


def _with_threads():
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(2) as ex:
        return _mesh_sim(executor=ex)


api("simulate.mesh.executor=threads", _with_threads, "ok", check=_finite)
for _key, _v in {"str": "yes", "none": None, "int": 1}.items():
    api(f"simulate.mesh.progress={_key}", lambda v=_v: _mesh_sim(progress=v), "error",
        "progress")
for _key, _v in {"int": 123, "empty": "", "list": ["run"]}.items():
    api(f"simulate.mesh.run_dir={_key}", lambda v=_v: _mesh_sim(run_dir=v), "error", "run_dir")
api("simulate.mesh.run_dir=file", lambda tmp: _mesh_sim(run_dir=tmp / "f.txt"), "error",
    ("run_dir", "f.txt"), setup=files({"f.txt": b"x"}))
api("simulate.mesh.run_dir=missing-parents", lambda tmp: _mesh_sim(run_dir=tmp / "a" / "b"),
    "ok", check=_finite)
api("simulate.mesh.run_dir=read-only", lambda tmp: _mesh_sim(run_dir=tmp / "ro" / "run"),
    "error", ("run_dir", "/ro"), setup=files({"ro": _read_only}), skip_root=True)

# ------------------------------------------------------------------ trace and weigh
api("trace.scene=str", lambda: ml.trace("x", _lad()), "error", "scene")
api("trace.ladar=str", lambda: ml.trace(_sphere(), "ladar"), "error", "ladar")
api("trace.analytic-scene", lambda: ml.trace(_disk(), _lad()), "error", "mesh")
api("trace.mode=x", lambda: ml.trace(_sphere(), _lad(), mode="x"), "error", "mode")
api("trace.normals=x", lambda: ml.trace(_sphere(), _lad(), normals="x"), "error", "normals")
api("trace.receiver=nan", lambda: ml.trace(_sphere(), _lad(), receiver=(nan, 0, 0)), "error",
    "receiver")
api("trace.jobs=0", lambda: ml.trace(_sphere(), _lad(), jobs=0), "error", "jobs")
api("trace.seed=-1", lambda: ml.trace(_sphere(), _lad(), seed=-1), "error", "seed")
api("trace.ray_spacing=nan", lambda: ml.trace(_sphere(), _lad(), ray_spacing=nan), "error",
    "ray_spacing")
api("trace.ok", lambda: ml.trace(_sphere(), _lad()), "ok",
    check=lambda h: h.rays.sum() > 0)
api("weigh.hits=str", lambda: ml.weigh("hits"), "error", "hits")
api("weigh.hits=None", lambda: ml.weigh(None), "error", "hits")
api("weigh.materials=[str]", lambda: ml.weigh(_hits(), ["x"]), "error", "materials[0]")
api("weigh.materials=str", lambda: ml.weigh(_hits(), "dark_gray"), "error", "materials")
api("weigh.materials=two", lambda: ml.weigh(_hits(), [_dg(), _al()]), "error", "materials")
api("weigh.materials=[]", lambda: ml.weigh(_hits(), []), "error", "materials")
api("weigh.materials=one", lambda: ml.weigh(_hits(), _al()), "ok", check=_finite)
api("weigh.footprint=str", lambda: ml.weigh(_hits(), footprint="no"), "error", "footprint")
for _key, _v in {"nan": [0.0, nan], "decreasing": [1.0, 0.0], "one": [0.0], "str": "x",
                 "2d": [[0.0, 1.0]], "inf": [-inf, 0.0], "empty": []}.items():
    api(f"weigh.bin_edges={_key}", lambda v=_v: ml.weigh(_hits(), bin_edges=v), "error",
        "bin_edges")
api("weigh.bin_edges=other", lambda: ml.weigh(_hits(), bin_edges=np.linspace(-1, 1, 5)),
    "ok", check=lambda s: s.n_bins == 4 and _finite(s))

# ------------------------------------------------------------------ sinograms
_ANG = [0.0, 90.0]
_E4 = np.linspace(-1, 1, 5)
for _key, _v in {"nan": [[nan, 0, 0, 0], [0, 0, 0, 0]], "inf": [[inf, 0, 0, 0]] * 2,
                 "1d": [1.0, 2.0], "3d": np.ones((2, 4, 1)), "str": "x", "none": None,
                 "ragged": [[1.0], [1.0, 2.0]], "empty": np.zeros((0, 4))}.items():
    api(f"Sinogram.values={_key}", lambda v=_v: ml.Sinogram(v, angles_deg=_ANG, bin_edges=_E4),
        "error", "values")
for _key, _v in {"short": [0.0], "nan": [0.0, nan], "none": None, "str": "x",
                 "2d": [[0.0, 90.0]]}.items():
    api(f"Sinogram.angles_deg={_key}", lambda v=_v: ml.Sinogram(np.ones((2, 4)), angles_deg=v,
                                                                bin_edges=_E4),
        "error", "angles_deg")
for _key, _v in {"short": [0.0, 1.0], "decreasing": _E4[::-1], "nan": [0, nan, 1, 2, 3],
                 "none": None, "str": "x"}.items():
    api(f"Sinogram.bin_edges={_key}", lambda v=_v: ml.Sinogram(np.ones((2, 4)), angles_deg=_ANG,
                                                               bin_edges=v),
        "error", "bin_edges")
for _key, _v in {"shape": [[1, 0, 0]], "nan": [[nan, 0, 0], [0, 1, 0]],
                 "zero": [[0, 0, 0], [0, 1, 0]]}.items():
    api(f"Sinogram.view_vectors={_key}", lambda v=_v: ml.Sinogram(
        np.ones((2, 4)), angles_deg=_ANG, bin_edges=_E4, view_vectors=v), "error",
        "view_vectors")
for _key, _v in {"str": "x", "none": None, "list": [1, 2]}.items():
    api(f"Sinogram.info={_key}", lambda v=_v: ml.Sinogram(np.ones((2, 4)), angles_deg=_ANG,
                                                          bin_edges=_E4, info=v),
        "error", "info")
api("Sinogram.model=int", lambda: ml.Sinogram(np.ones((2, 4)), angles_deg=_ANG, bin_edges=_E4,
                                              model=3), "error", "model")
api("Sinogram.negative-values", lambda: ml.Sinogram(-np.ones((2, 4)), angles_deg=_ANG,
                                                    bin_edges=_E4), "ok",
    check=lambda s: s.values.min() == -1)
api("Sinogram.int-values", lambda: ml.Sinogram(np.ones((2, 4), int), angles_deg=_ANG,
                                               bin_edges=_E4), "ok",
    check=lambda s: s.values.dtype == np.float64)

# ------------------------------------------------------------------ reconstruction
for _key, _v in dict(COUNTS, huge=10**5).items():
    api(f"fbp.size={_key}", lambda v=_v: ml.fbp(_sino(), size=v), "error", "size")
api("fbp.size=1", lambda: ml.fbp(_sino(), size=1), "ok", check=lambda im: im.values.shape
    == (1, 1))
scalar_cases("fbp", lambda v: ml.fbp(_sino(), size=8, extent=v), "extent",
             ok=("huge", "none"), checks={"huge": _finite,             # none: the bins' reach
                                         "none": lambda im: im.extent == max(
                                             abs(_sino().bin_edges[[0, -1]]))})
for _key, _v in {"x": "x", "none": None, "upper": "RAMP"}.items():
    api(f"fbp.filter={_key}", lambda v=_v: ml.fbp(_sino(), size=8, filter=v), "error", "filter")
api("fbp.interpolation=cubic", lambda: ml.fbp(_sino(), size=8, interpolation="cubic"), "error",
    "interpolation")
for _key, _v in {"nan": (nan, 0.0), "short": (0.0,), "str": "x", "none": None,
                 "inf": (0.0, inf)}.items():
    api(f"fbp.center={_key}", lambda v=_v: ml.fbp(_sino(), size=8, center=v), "error", "center")
api("fbp.sinogram=str", lambda: ml.fbp("x"), "error", "sinogram")
api("fbp.sinogram=array", lambda: ml.fbp(np.ones((32, 8))), "error", "sinogram")
api("fbp.off-plane", lambda: ml.fbp(ml.Sinogram(np.ones((1, 4)), angles_deg=[0.0],
                                                bin_edges=_E4, view_vectors=[[0, 0, 1]])),
    "error", "view")
api("fbp.one-view-warns", lambda: ml.fbp(ml.Sinogram(np.ones((1, 4)), angles_deg=[0.0],
                                                     bin_edges=_E4), size=8), "warn")
api("fbp.gap-warns", lambda: ml.fbp(ml.Sinogram(np.ones((3, 4)), angles_deg=[0.0, 10.0, 20.0],
                                                bin_edges=_E4), size=8), "warn")
def _uniform_sino(value):
    return ml.Sinogram(np.full((32, 8), value), angles_deg=np.arange(32) * 360.0 / 32,
                       bin_edges=np.linspace(-1, 1, 9))


api("fbp.values=1e-300", lambda: ml.fbp(_uniform_sino(1e-300), size=8), "ok",
    check=lambda im: _finite(im) and im.values.max() > 0)
api("fbp.values=1e307", lambda: ml.fbp(_uniform_sino(1e307), size=8), "ok", check=_finite)
api("fbp.values=1.7e308", lambda: ml.fbp(_uniform_sino(1.7e308), size=8), "error",
    ("values", "sinogram"))
api("log_radiance.values=1.7e308", lambda: ml.log_radiance(_uniform_sino(1.7e308)), "ok",
    check=_finite)
api("fbp.non-uniform-bins", lambda: ml.fbp(ml.Sinogram(
    np.ones((32, 4)), angles_deg=np.arange(32) * 360.0 / 32, bin_edges=[-1, -0.5, 0, 0.2, 1]),
    size=8),
    "ok", check=lambda im: im.info["resampled"] and _finite(im))

scalar_cases("log_radiance", lambda v: ml.log_radiance(_sino(), floor=v), "floor")
api("log_radiance.sinogram=str", lambda: ml.log_radiance("x"), "error", "sinogram")
api("log_radiance.sinogram=array", lambda: ml.log_radiance(np.ones((2, 2))), "error",
    "sinogram")
api("log_radiance.all-zero", lambda: ml.log_radiance(ml.Sinogram(
    np.zeros((2, 4)), angles_deg=_ANG, bin_edges=_E4)), "ok",
    check=lambda s: not s.values.any())
scalar_cases("clip_radiance", lambda v: ml.clip_radiance(_sino(), threshold=v), "threshold")
api("clip_radiance.sinogram=str", lambda: ml.clip_radiance("x"), "error", "sinogram")
api("clip_radiance.threshold=1", lambda: ml.clip_radiance(_sino(), threshold=1.0), "ok",
    check=lambda s: np.array_equal(s.values, _sino().values))


def _resample(*args, **kw):
    from meshladar.reconstruct import resample_uniform

    return resample_uniform(*args, **kw)


for _key, _v in COUNTS.items():
    if _key != "none":
        api(f"resample_uniform.n_bins={_key}", lambda v=_v: _resample(_sino(), v), "error",
            ("n_bins must", "n_bins:"))
api("resample_uniform.n_bins=None", lambda: _resample(_sino(), None), "ok",
    check=lambda s: s.n_bins == 8)
api("resample_uniform.sino=str", lambda: _resample("x"), "error", "sino")

# ------------------------------------------------------------------ result files


def _load(path):
    return ml.io.load_result(path)


_file_cases("io.load_result", "api", _load, ".npz",
            {"missing": None, "dir": DIR, "empty": b"", "junk": JUNK,
             "truncated": _truncated_result, "text": b"hello\n", "not-utf8": NOT_UTF8_TOML,
             "no-meta": _no_meta_result, "pickled": _pickled_result,
             "deep-meta": _deep_meta_result}, ("bad.npz",))
_file_cases("io.load_result", "api", _load, ".dat", {"result": _result}, (), expect="ok")
api("io.load_result.None", lambda: ml.io.load_result(None), "error", ("path", "None"))
api("io.load_result.int", lambda: ml.io.load_result(3), "error", ("path", "3"))
_file_cases("io.load_sinogram", "api", lambda p: ml.io.load_sinogram(p), ".npz", {"image": _image_result, "no-meta": _no_meta_result}, ("bad.npz",))
api("io.save_result.path=empty", lambda: ml.io.save_result("", {"a": np.ones(2)}, {}), "error",
    "path")
api("io.save_result.path=dir", lambda tmp: ml.io.save_result(tmp, {"a": np.ones(2)}, {}),
    "error", ("path", "folder", "directory"))
api("io.save_result.path=None", lambda: ml.io.save_result(None, {"a": np.ones(2)}, {}),
    "error", "path")
api("io.save_result.missing-folder", lambda tmp: ml.io.save_result(tmp / "a" / "r.npz",
                                                                   {"a": np.ones(2)}, {}),
    "ok")
api("io.save_result.object-array", lambda tmp: ml.io.save_result(
    tmp / "r.npz", {"a": np.array([{}], dtype=object)}, {}), "error", ("a", "array"))
api("io.save_result.meta-not-json", lambda tmp: ml.io.save_result(
    tmp / "r.npz", {"a": np.ones(2)}, {"x": object()}), "error", "meta")
api("io.save_result.reserved-key", lambda tmp: ml.io.save_result(
    tmp / "r.npz", {"__meta__": np.ones(2)}, {}), "error", "__meta__")
api("io.save_result.arrays=str", lambda tmp: ml.io.save_result(tmp / "r.npz", "x", {}),
    "error", "arrays")
api("io.save_result.meta=str", lambda tmp: ml.io.save_result(tmp / "r.npz", {}, "x"),
    "error", "meta")
api("io.save_result.read-only", lambda tmp: ml.io.save_result(tmp / "ro" / "r.npz",
                                                              {"a": np.ones(2)}, {}),
    "error", "/ro", setup=files({"ro": _read_only}), skip_root=True)
api("io.save_sinogram.sino=str", lambda tmp: ml.io.save_sinogram(tmp / "r.npz", "x"), "error",
    "sino")

# ------------------------------------------------------------------ coating tables


def _table(path):
    return ml.materials.load_table(path)


_file_cases("materials.load_table", "api", _table, ".toml",
            dict(BAD_TOML, **{
                "long-int": b"[m]\nrho_d = " + b"9" * 5000 + b"\n",
                "unknown-field": TABLE + b"colour = 1\n",
                "string-field": TABLE.replace(b"0.1\ne", b"\"0.1\"\ne"),
                "nan-field": TABLE.replace(b"rho_d = 0.1", b"rho_d = nan"),
                "bool-field": TABLE.replace(b"rho_d = 0.1", b"rho_d = true"),
                "lobes": TABLE + b"lobes = \"x\"\n",
                "not-a-table": b"x = [1]\n",
                "missing-field": b"[m]\nrho_d = 0.1\n",
                "energy": TABLE.replace(b"epsilon = 0.5", b"epsilon = 0.99")}), ("bad.toml",))
_file_cases("materials.load_table", "api", _table, ".txt", {"valid": TABLE}, (), expect="ok",
            check=lambda t: "mine" in t)
api("materials.load_table.None", lambda: ml.materials.load_table(None), "error", "path")
api("materials.parse_table.str", lambda: ml.materials.parse_table("x"), "error", "table")
api("materials.parse_table.empty", lambda: ml.materials.parse_table({}), "error", "table")
api("materials.parse_table.entry-int", lambda: ml.materials.parse_table({"a": 1}), "error",
    "[a]")

# ------------------------------------------------------------------ phantom specs


def _phantom(path, **kw):
    return ml.phantoms.load(path, **kw)


_file_cases("phantoms.load", "api", _phantom, ".toml", dict(BAD_TOML, **{
    "long-int": LONG_INT_TOML,
    "no-shapes": b"[ladar]\nn_bins = 8\n",
    "shape-not-table": b"shape = 3\n",
    "unknown-kind": _spec(kind='"square"'),
    "missing-radius": DISK_SPEC.replace(b"radius = 0.5\n", b""),
    "radius-nan": _spec(radius="nan"),
    "radius-bool": _spec(radius="true"),
    "radius-neg": _spec(radius="-1"),
    "center-short": _spec(center="[0]"),
    "material-unknown": _spec(material='"unobtainium"'),
    "material-int": _spec(material="3"),
    "n_bins-zero": _spec(n_bins="0"),
    "n_bins-float": _spec(n_bins="1e10"),
    "n_bins-huge": _spec(n_bins="10000000000"),
    "bin_width-neg": _spec(bin_width="-1"),
    "step-zero": _spec(angles_deg="{ start = 0.0, stop = 360.0, step = 0.0 }"),
    "step-nan": _spec(angles_deg="{ start = 0.0, stop = 360.0, step = nan }"),
    "stop-inf": _spec(angles_deg="{ start = 0.0, stop = inf, step = 1.0 }"),
    "step-str": _spec(angles_deg='{ start = 0.0, stop = 360.0, step = "1" }'),
    "angles-str": _spec(angles_deg='["a", "b"]'),
    "angles-empty": _spec(angles_deg="[]"),
    "bin_edges-decreasing": DISK_SPEC.replace(b"n_bins = 16\nbin_width = 0.1\n",
                                              b"bin_edges = [1.0, 0.0]\n"),
    "overlap": DISK_SPEC + DISK_SPEC[DISK_SPEC.index(b"[[shape]]"):],
    "ladar-not-table": b"ladar = 3\n" + DISK_SPEC[DISK_SPEC.index(b"[[shape]]"):],
}), ("bad.toml",))
_file_cases("phantoms.load", "api", _phantom, ".toml", {"valid": DISK_SPEC}, (), expect="ok",
            check=lambda ph: ph.ladar.n_bins == 16 and ph.ladar.n_views == 4)
api("phantoms.load.unknown-name", lambda: ml.phantoms.load("nope"), "error", "nope")
api("phantoms.load.None", lambda: ml.phantoms.load(None), "error", ("name", "path"))
api("phantoms.load.int", lambda: ml.phantoms.load(3), "error", ("name", "path"))
api("phantoms.load.materials=unknown-shape", lambda: ml.phantoms.load(
    "disk_pair", materials={"nope": "dark_gray"}), "error", "nope")
api("phantoms.load.materials=unknown-coating", lambda: ml.phantoms.load(
    "disk_pair", materials={"small": "unobtainium"}), "error", "unobtainium")
api("phantoms.load.materials=str", lambda: ml.phantoms.load("disk_pair",
                                                            materials="dark_gray"),
    "error", "materials")
api("phantoms.load.materials=inline-bad", lambda: ml.phantoms.load(
    "disk_pair", materials={"small": {"rho_d": 2.0}}), "error", ("rho_d", "small"))
api("phantoms.load.materials=coating", lambda: ml.phantoms.load(
    "disk_pair", materials={"small": _al()}), "ok",
    check=lambda ph: _al() in ph.scene.materials)

# ------------------------------------------------------------------ studies (refused before
# any work is done)


def _study(**kw):
    from meshladar import studies

    return studies.faceting_study(**kw)


api("studies.study_scene.phantom", lambda: ml.studies.study_scene("x", "dark_gray"), "error",
    "phantom")
api("studies.study_scene.coating", lambda: ml.studies.study_scene("disk", "x"), "error",
    "coating")
api("studies.faceting_study.setting", lambda: _study(setting="x"), "error", "setting")
api("studies.faceting_study.phantoms", lambda: _study(phantoms=["nope"]), "error",
    ("phantom", "nope"))
api("studies.faceting_study.phantoms=str", lambda: _study(phantoms="disk"), "error",
    "phantoms")
api("studies.faceting_study.coatings", lambda: _study(coatings=["nope"]), "error",
    ("coating", "nope"))
api("studies.faceting_study.run_dir=int", lambda: _study(run_dir=123), "error", "run_dir",
    forbid=("meshladar.forward:simulate",))
api("studies.faceting_study.executor=str", lambda: _study(executor="x", phantoms=["disk"]),
    "error", "executor")
api("studies.save_study.result=str", lambda tmp: ml.studies.save_study("x", tmp / "s"),
    "error", "result")

# ------------------------------------------------------------------ the viewer (off screen;
# the bad arguments are refused before anything is drawn)


def _viewer():
    from meshladar.viz import viewer

    return viewer


def _show(**kw):
    return _viewer().show_scene(_disk(), off_screen=True, **kw)


for _key, _v in {"nan": nan, "inf": inf, "str": "x", "list": [1, 2]}.items():
    api(f"viewer.show_scene.view_angle_deg={_key}", lambda v=_v: _show(view_angle_deg=v),
        "error", "view_angle_deg")
for _key, _v in {"zero": (0, 0, 0), "nan": (nan, 0, 0), "short": (1, 0), "str": "x"}.items():
    api(f"viewer.show_scene.view_vector={_key}", lambda v=_v: _show(view_vector=v), "error",
        "view_vector")
api("viewer.show_scene.segments=2", lambda: _show(segments=2), "error", "segments")
api("viewer.show_scene.iso_ranges=-1", lambda: _show(iso_ranges=-1), "error", "iso_ranges")
api("viewer.show_scene.window_size=0", lambda: _show(window_size=(0, 0)), "error",
    "window_size")
api("viewer.show_scene.scene=str", lambda: _viewer().show_scene("disk", off_screen=True),
    "error", "scene")

# ------------------------------------------------------------------ bounces, lrcs (issue 33)
_BOUNCES = {"zero": 0, "neg": -1, "nine": 9, "float": 2.0, "nan": nan, "str": "two",
            "bool": True, "list": [2]}
for _key, _v in _BOUNCES.items():
    api(f"simulate.mesh.bounces={_key}",
        lambda v=_v: _mesh_sim(bounces=v, radiometry="power"), "error", "bounces")
for _key, _v in COUNTS.items():
    api(f"simulate.mesh.bounce_samples={_key}",
        lambda v=_v: _mesh_sim(bounces=2, bounce_samples=v),
        "ok" if _v is None else "error", "bounce_samples")
api("simulate.mesh.bounces=auto-convex", lambda: _mesh_sim(bounces="auto"), "ok",
    check=lambda s: s.info["bounces"] == 1)
for _key, _v in {"nan": [nan], "inf": [0.0, inf], "str": "x", "2d": [[1.0, 0.0]],
                 "empty": [], "none": None}.items():
    api(f"lrcs.views={_key}", lambda v=_v: ml.lrcs(_sphere(), v), "error", "views")
for _key, _v in _BOUNCES.items():
    api(f"lrcs.bounces={_key}", lambda v=_v: ml.lrcs(_sphere(), [0.0], bounces=v), "error",
        "bounces")
api("lrcs.per_part=str", lambda: ml.lrcs(_sphere(), [0.0], per_part="yes"), "error",
    "per_part")
api("lrcs.radiometry", lambda: ml.lrcs(_sphere(), [0.0], radiometry="paper"), "error",
    "radiometry")
for _key, _v in {"zero": 0, "nine": 9, "float": 2.0, "bool": True}.items():
    api(f"specular_chain.bounces={_key}", lambda v=_v: ml.forward.specular.specular_chain(
        _sphere(), _lad(), bounces=v, ray_spacing=0.1), "error", "bounces")
for _key, _v in {"zero": 0.0, "neg": -1.0, "nan": nan, "wide": 2.0}.items():
    api(f"specular_chain.cone={_key}", lambda v=_v: ml.forward.specular.specular_chain(
        _sphere(), _lad(), cone=v, ray_spacing=0.1), "error", "cone")
