"""The bad-input matrix, the imaging ladar: meshladar.scan's records and entry point, its
files, and ``meshladar scan``; every bad argument refused by name before a ray is cast."""

from __future__ import annotations

from math import inf, nan

import numpy as np

from _matrix import BAD_FILES, _file_cases, _stl, api, cli, files, ml

_WORK = ("meshladar.scan:scan",)


def _scan_kit():
    from meshladar import scan as sc

    sphere = ml.Scene.from_parts([ml.meshes.sphere((0.0, 0.0, 0.0), 1.0, 0, subdivisions=2)],
                                 [ml.brdf.Lambertian(0.5)])
    return (sc, sphere, sc.raster([0.0], [0.0], pulse_rate=10.0),
            sc.Platform.static((-10.0, 0.0, 0.0)),
            sc.ScanSensor(pulse_energy=1e-6, aperture_diameter=0.05, sample_rate=2e9))


def _scan(**over):
    sc, scene, pat, plat, sen = _scan_kit()
    args = dict(scene=scene, pattern=pat, platform=plat, sensor=sen)
    kw = {k: over.pop(k) for k in list(over) if k not in args}
    args.update(over)
    return sc.scan(args["scene"], args["pattern"], args["platform"], args["sensor"], **kw)


def _sensor(**kw):
    from meshladar.scan import ScanSensor

    base = dict(pulse_energy=1e-6, aperture_diameter=0.05, sample_rate=2e9)
    base.update(kw)
    return ScanSensor(**base)


def _sc():
    from meshladar import scan as sc
    return sc


api("scan.ok", lambda: _scan(), "ok", check=lambda pc: len(pc) == 1)
api("scan.scene=analytic", lambda: _scan(scene=ml.Scene([ml.Disk((0, 0), 1.0,
                                                                 ml.brdf.Lambertian(0.5))])),
    "error", "scene")
api("scan.scene=str", lambda: _scan(scene="sphere.stl"), "error", "scene")
api("scan.pattern=list", lambda: _scan(pattern=[[1, 0, 0]]), "error", "pattern")
api("scan.platform=tuple", lambda: _scan(platform=(0, 0, 0)), "error", "platform")
api("scan.sensor=None", lambda: _scan(sensor=None), "error", "sensor")
api("scan.seed=-1", lambda: _scan(seed=-1), "error", "seed")
api("scan.keep_waveforms=str", lambda: _scan(keep_waveforms="yes"), "error", "keep_waveforms")
api("scan.chunk_pulses=0", lambda: _scan(chunk_pulses=0), "error", "chunk_pulses")
for _key, _v in {"zero": 0.0, "nan": nan, "inf": inf, "str": "1"}.items():
    api(f"ScanSensor.pulse_energy={_key}", lambda v=_v: _sensor(pulse_energy=v), "error",
        "pulse_energy")
    api(f"ScanSensor.sample_rate={_key}", lambda v=_v: _sensor(sample_rate=v), "error",
        "sample_rate")
api("ScanSensor.beam=float", lambda: _sensor(beam=0.001), "error", "beam")
api("ScanSensor.samples=2", lambda: _sensor(samples=2), "error", "samples")
api("ScanSensor.samples=40", lambda: _sensor(samples=40), "error",
    ("samples", "cannot hold one echo", "give 70 or more"))
api("ScanSensor.geiger+speckle", lambda: _sensor(geiger=_sc().GeigerMode(),
                                                 noise=ml.noise.Noise(speckle_cells=1)),
    "error", "geiger")
api("ScanBeam.divergence=-1", lambda: _sc().ScanBeam(-1.0), "error", "divergence")
api("ScanBeam.divergence=nan", lambda: _sc().ScanBeam(nan), "error", "divergence")
api("ScanBeam.profile=x", lambda: _sc().ScanBeam(1e-3, profile="x"), "error", "profile")
api("ScanBeam.tol=0", lambda: _sc().ScanBeam(1e-3, tol=0.0), "error", "tol")
api("ScanBeam.sub_rays=0", lambda: _sc().ScanBeam(1e-3, sub_rays=0), "error", "sub_rays")
api("ScanBeam.sub_rays=huge", lambda: _sc().ScanBeam(1e-3, sub_rays=10 ** 6), "error",
    "sub_rays")
api("Detector.max_returns=16", lambda: _sc().Detector(max_returns=16), "error", "max_returns")
api("Detector.false_alarm=0", lambda: _sc().Detector(false_alarm=0.0), "error", "false_alarm")
api("Detector.threshold=-1", lambda: _sc().Detector(threshold=-1.0), "error", "threshold")
api("GeigerMode.shots=0", lambda: _sc().GeigerMode(shots=0), "error", "shots")
api("GeigerMode.dead_time=-1", lambda: _sc().GeigerMode(dead_time=-1.0), "error", "dead_time")
api("Platform.position=nan", lambda: _sc().Platform.static((nan, 0, 0)), "error", "position")
api("Platform.times-decrease", lambda: _sc().Platform.waypoints(
    [1.0, 0.0], [[0, 0, 0], [1, 0, 0]], np.zeros((2, 3))), "error", "times")
api("Platform.interpolation=cubic", lambda: _sc().Platform.waypoints(
    [0.0, 1.0], [[0, 0, 0], [1, 0, 0]], np.zeros((2, 3)), "cubic"), "error", "interpolation")
api("Platform.mount_offset=two", lambda: _sc().Platform.static((0, 0, 0),
                                                               mount_offset=(1, 2)),
    "error", "mount_offset")
api("write_las.cloud=array", lambda: _sc().write_las("x.las", np.zeros(3)), "error", "cloud")
api("write_las.path=h5", lambda: _sc().write_las("x.h5", _scan()), "error",
    ("path", "HDF5", "write_hdf5"))
api("write_hdf5.path=las", lambda: _sc().write_hdf5("x.las", _scan()), "error",
    ("path", "LAS", "write_las"))
api("raster.bidirectional=yes", lambda: _sc().raster([0.0, 1.0], [0.0], pulse_rate=1e3,
                                                     bidirectional="yes"),
    "error", "bidirectional must be True or False")
api("raster.azimuth_deg=2-D", lambda: _sc().raster([[0.0, 1.0]], [0.0], pulse_rate=1e3),
    "error", ("azimuth_deg", "1-D", "(1, 2)"))
_file_cases("scan.read_las", "api", lambda p: _sc().read_las(p), ".las", BAD_FILES, "path")
_file_cases("scan.read_hdf5", "api", lambda p: _sc().read_hdf5(p), ".h5", BAD_FILES, "path")
_file_cases("scan.Platform.from_csv", "api", lambda p: _sc().Platform.from_csv(p), ".csv",
            BAD_FILES, ("path", "header"))

_SCAN = ["scan", "{tmp}/sphere.stl", "--quiet", "-o", "{tmp}/p.las",
         "--platform", "static position=-10,0,0"]
_RASTER = ["--pattern", "raster azimuth_deg=-1:1:3 elevation_deg=0 pulse_rate=10"]
_SPHERE = files({"sphere.stl": _stl})
cli("scan.ok", _SCAN + _RASTER, "ok", setup=_SPHERE,
    check=lambda tmp: (tmp / "p.las").stat().st_size > 0)
for _key, _spec in {"kind": "nope", "key": "rotating elevations=3",
                    "value": "raster azimuth_deg=x elevation_deg=0 pulse_rate=1",
                    "missing": "rotating elevations_deg=0", "empty": "",
                    "range": "raster azimuth_deg=0:1:0 elevation_deg=0 pulse_rate=1",
                    "bad-value": "oscillating half_angle_deg=95 scan_hz=1 pulse_rate=1 "
                                 "duration=1"}.items():
    cli(f"scan.--pattern={_key}", _SCAN + ["--pattern", _spec], "error", "--pattern",
        setup=_SPHERE, forbid=_WORK)
cli("scan.--platform=missing-key", _SCAN[:-2] + ["--platform", "static"] + _RASTER, "error",
    "--platform", setup=_SPHERE, forbid=_WORK)
cli("scan.--platform=no-file", _SCAN[:-2] + ["--platform", "{tmp}/none.csv"] + _RASTER,
    "error", "--platform", setup=_SPHERE, forbid=_WORK)
cli("scan.-o=txt", _SCAN[:3] + ["-o", "{tmp}/p.txt"] + _SCAN[5:] + _RASTER, "error", "-o",
    setup=_SPHERE, forbid=_WORK)
cli("scan.-o=input", _SCAN[:3] + ["-o", "{tmp}/sphere.stl"] + _SCAN[5:] + _RASTER, "error",
    "-o", setup=_SPHERE, forbid=_WORK)
cli("scan.--waveforms=las", _SCAN + _RASTER + ["--waveforms", "{tmp}/w.las"], "error",
    "--waveforms", setup=_SPHERE, forbid=_WORK)
for _flag, _v in (("--tol", "0"), ("--divergence", "-1"), ("--max-returns", "16"),
                  ("--pulse-energy", "nan"), ("--sub-rays", "0")):
    cli(f"scan.{_flag}={_v}", _SCAN + _RASTER + [_flag, _v], "error",
        (_flag, _flag.lstrip("-").replace("-", "_")), setup=_SPHERE, forbid=_WORK)
api("scan.keep_waveforms+run_dir-without-samples", lambda: _scan(
    keep_waveforms=True, run_dir="never-made"), "error", ("samples", "run_dir"))
api("scan.jobs=0", lambda: _scan(jobs=0), "error", "jobs")
api("scan.progress=str", lambda: _scan(progress="yes"), "error", "progress")
api("Detector.cfar=str", lambda: _sc().Detector(cfar="yes"), "error", "cfar")
api("Detector.cfar+threshold", lambda: _sc().Detector(cfar=True, threshold=3.0), "error",
    ("cfar", "threshold"))
api("ScanSensor.geiger+cfar", lambda: _sensor(geiger=_sc().GeigerMode(),
                                              detector=_sc().Detector(cfar=True)),
    "error", "cfar")
api("scan.motions=unknown-part", lambda: _scan(motions={7: ml.motion.Motion()}), "error",
    "motions")
api("scan.motions=list", lambda: _scan(motions=[ml.motion.Motion()]), "error", "motions")
cli("view.--points=missing", ["view", "{tmp}/sphere.stl", "--points", "{tmp}/none.las",
                              "--screenshot", "{tmp}/v.png"], "error", "--points",
    setup=_SPHERE)
cli("view.--points=junk", ["view", "{tmp}/sphere.stl", "--points", "{tmp}/junk.las",
                           "--screenshot", "{tmp}/v.png"], "error", "--points",
    setup=files({"sphere.stl": _stl, "junk.las": b"not a las file" * 20}))
cli("view.--color-by=x", ["view", "{tmp}/sphere.stl", "--points", "{tmp}/p.las",
                          "--color-by", "colour"], "error", "--color-by", setup=_SPHERE)
api("scan.waveforms_file+keep", lambda: _scan(waveforms_file="w.h5", keep_waveforms=True),
    "error", ("waveforms_file", "keep_waveforms"))
api("scan.waveforms_file+run_dir", lambda: _scan(waveforms_file="w.h5", run_dir="r"),
    "error", ("waveforms_file", "run_dir"))
api("scan.waveforms_file=no-folder", lambda: _scan(waveforms_file="/no/such/folder/w.h5"),
    "error", "waveforms_file")
api("scan.waveforms_file=folder", lambda: _scan(waveforms_file="."), "error",
    ("waveforms_file", "folder"))
api("scan.waveforms_file=las", lambda: _scan(waveforms_file="w.las"), "error",
    ("waveforms_file", "LAS", "write_las"))
api("ScanSensor.echoes=x", lambda: _sensor(echoes="x"), "error", "echoes")
api("ScanSensor.discrete+noise", lambda: _sensor(echoes="discrete", noise=ml.noise.Noise()),
    "error", ("discrete", "noise"))
api("scan.discrete+waveforms_file", lambda: _scan(sensor=_sensor(echoes="discrete"),
                                                  waveforms_file="w.h5"),
    "error", "waveforms_file")
api("scan.waveforms_file+executor", lambda: _scan(waveforms_file="w.h5", executor=object()),
    "error", ("waveforms_file", "executor"))
