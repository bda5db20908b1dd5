"""The bad-input matrix, the command line: every subcommand's bad arguments, each run in
this process through ``meshladar.cli.main``; the long commands' bad arguments must be
refused before any work starts."""

from __future__ import annotations

# meshladar (``ml``) as _matrix imported it: the --before checkout's, if one is given
from _matrix import (BAD_TOML, DEEP_TOML, DIR, DISK_SPEC, JUNK, LONG_INT_TOML, NOT_UTF8_OBJ,
                     NOT_UTF8_TOML, TABLE, _deep_meta_result, _file_cases, _image_result,
                     _no_meta_result, _pickled_result, _read_only, _refuses_many_jobs,
                     _result, _spec, _stl, _truncated_result, _truncated_stl, cli, files)

#: What the long commands run: a bad argument must never reach it.
_WORK = ("meshladar.studies.paper:simulate", "meshladar.forward:simulate",
         "meshladar.cli.simulate:simulate", "meshladar.studies.bench:bench_analytic")

_SIM = ["simulate", "disk", "-o", "{tmp}/r.npz", "--quiet", "--views", "4"]
_MESH = ["simulate", "{tmp}/sphere.stl", "-o", "{tmp}/r.npz", "--quiet", "--views", "2",
         "--bins", "8"]
_SPHERE_FILE = files({"sphere.stl": _stl})
_REC = ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}/r.png", "--quiet", "--size", "16"]
_RESULT_FILE = files({"r.npz": _result})


def _wrote(name):
    return lambda tmp: (tmp / name).is_file() and (tmp / name).stat().st_size > 0


def _flag_names(flag):
    return (flag, flag.lstrip("-").replace("-", "_"))


# ------------------------------------------------------------------ top level
cli("top.no-command", [], "error", "COMMAND")
cli("top.unknown-command", ["nope"], "error", "nope")
cli("top.unknown-option", ["--bogus", "demo"], "error", "--bogus")
cli("top.version", ["--version"], "ok")
for _argv in (["demo"], ["materials"], ["paper", "{tmp}/out"],
              ["simulate", "disk", "-o", "{tmp}/r.npz"], ["reconstruct", "{tmp}/r.npz", "-o",
                                                          "{tmp}/r.png"],
              ["view", "disk"], ["study", "faceting", "{tmp}/s"], ["bench"]):
    cli(f"{_argv[0]}.help", [_argv[0], "--help"], "ok")
    cli(f"{_argv[0]}.unknown-option", _argv + ["--bogus"], "error", "--bogus",
        forbid=_WORK)

# ------------------------------------------------------------------ demo
for _key, _v in {"nan": "nan", "inf": "inf", "str": "x", "empty": "", "commas": ",,",
                 "huge": "1e400", "hex": "0x10", "minus-inf": "0,-inf",
                 "gaps": "0,,5"}.items():
    cli(f"demo.--angles-deg={_key}", ["demo", "--angles-deg", _v], "error", "--angles-deg")
for _key, _v in {"neg": "-30", "zero": "0", "big": "1e300", "space": " 5 , 10 "}.items():
    cli(f"demo.--angles-deg={_key}", ["demo", f"--angles-deg={_v}"], "ok")

# ------------------------------------------------------------------ materials
_file_cases("materials.table", "cli", lambda p: ["materials", p], ".toml", BAD_TOML,
            ("bad.toml",))
_file_cases("materials.table", "cli", lambda p: ["materials", p], ".toml",
            {"energy": TABLE.replace(b"epsilon = 0.5", b"epsilon = 0.99")}, ("bad.toml",))
_file_cases("materials.table", "cli", lambda p: ["materials", p], ".txt", {"valid": TABLE}, (),
            expect="ok")
cli("materials.packaged", ["materials"], "ok")
cli("materials.two-tables", ["materials", "a.toml", "b.toml"], "error", "b.toml")

# ------------------------------------------------------------------ paper, study, bench:
# only bad arguments, which must be refused before any work (the work raises if reached)
_PAPER = ("meshladar.studies.paper:simulate",)
_STUDY = ("meshladar.studies.faceting:simulate", "meshladar.forward:simulate")
for _key, _v in {"zero": "0", "neg": "-1", "str": "x", "float": "1.5", "nan": "nan",
                 "empty": ""}.items():
    cli(f"paper.--size={_key}", ["paper", "{tmp}/out", "--size", _v], "error", "--size",
        forbid=_PAPER)
cli("paper.--size=huge", ["paper", "{tmp}/out", "--size", "100000"], "error", "size",
    forbid=_PAPER)
cli("paper.outdir=file", ["paper", "{tmp}/f.txt"], "error", "f.txt",
    setup=files({"f.txt": b"x"}), forbid=_PAPER)
cli("paper.outdir=empty", ["paper", ""], "error", ("outdir", "''"), forbid=_PAPER)
cli("paper.outdir=read-only", ["paper", "{tmp}/ro/out"], "error", "/ro",
    setup=files({"ro": _read_only}), skip_root=True, forbid=_PAPER)
cli("paper.no-outdir", ["paper"], "error", "outdir")
cli("study.kind", ["study", "nope", "{tmp}/s"], "error", "nope")
cli("study.no-outdir", ["study", "faceting"], "error", "outdir")
cli("study.outdir=file", ["study", "faceting", "{tmp}/f.txt", "--quiet"], "error", "f.txt",
    setup=files({"f.txt": b"x"}), forbid=_STUDY)
cli("study.outdir=empty", ["study", "faceting", "", "--quiet"], "error", ("outdir", "''"),
    forbid=_STUDY)
cli("study.outdir=read-only", ["study", "faceting", "{tmp}/ro/s", "--quiet"], "error", "/ro",
    setup=files({"ro": _read_only}), skip_root=True, forbid=_STUDY)
for _key, _v in {"zero": "0", "neg": "-1", "str": "x", "float": "1.5", "empty": ""}.items():
    cli(f"bench.--repeats={_key}", ["bench", "--repeats", _v], "error", "--repeats",
        forbid=_WORK)

# ------------------------------------------------------------------ simulate: options
_INT_BAD = {"zero": "0", "neg": "-1", "str": "x", "float": "1.5", "nan": "nan", "empty": "",
            "huge-exp": "1e400"}
_POS_BAD = {"zero": "0", "neg": "-1", "str": "x", "nan": "nan", "inf": "inf", "empty": "",
            "huge-exp": "1e400"}
_FEW = ("zero", "str", "nan", "empty")      # for options whose parser another shares
for _flag in ("--views", "--bins", "--segments", "--view-vectors", "--jobs", "--workers"):
    for _key, _v in _INT_BAD.items():
        if _flag == "--views" or _key in _FEW:
            cli(f"simulate.{_flag}={_key}", _SIM[:-2] + [_flag, _v], "error", _flag)
for _flag in ("--bin-width", "--ray-spacing", "--rays-per-bin", "--tol", "--max-rays",
              "--pixel-size"):
    for _key, _v in _POS_BAD.items():
        if _flag in ("--bin-width", "--ray-spacing") or _key in _FEW + ("neg", "inf"):
            cli(f"simulate.{_flag}={_key}", _SIM + [_flag, _v], "error", _flag)
for _key, _v in {"nan": "nan", "inf": "inf", "str": "x", "empty": ""}.items():
    cli(f"simulate.--z0={_key}", _SIM + ["--z0", _v], "error", "--z0")
for _key, _v in {"neg": "-1", "str": "x", "float": "1.5", "empty": ""}.items():
    cli(f"simulate.--seed={_key}", _MESH + ["--seed", _v], "error", "--seed")
for _key, _v in {"two": "1,0", "zero": "0,0,0", "nan": "nan,0,0", "str": "x", "empty": "",
                 "four": "1,0,0,0", "inf": "inf,0,0"}.items():
    cli(f"simulate.--receiver={_key}", _MESH + [f"--receiver={_v}"], "error", "--receiver")
for _key, _v in {"nan": "nan", "inf": "inf", "str": "x", "empty": "", "commas": ","}.items():
    cli(f"simulate.--angles-deg={_key}", _SIM[:-2] + ["--angles-deg", _v], "error",
        "--angles-deg")
for _flag, _v in (("--model", "x"), ("--mode", "x"), ("--normals", "x"),
                  ("--sampling", "x")):
    cli(f"simulate.{_flag}=x", _SIM + [_flag, _v], "error", _flag)
cli("simulate.--scheduler=not-an-address", _MESH + ["--scheduler", "nonsense"], "error",
    ("--scheduler", "scheduler"), setup=_SPHERE_FILE)

# values argparse accepts that the run must refuse (up front, before any work)
cli("simulate.--views=huge", _SIM[:-2] + ["--views", "1000000000"], "error",
    _flag_names("--views") + ("views",))
cli("simulate.--view-vectors=huge", _MESH[:-4] + ["--bins", "8", "--view-vectors",
                                                  "1000000000"], "error",
    _flag_names("--view-vectors") + ("views",), setup=_SPHERE_FILE)
cli("simulate.--bins=huge", _SIM + ["--bins", "10000000000"], "error",
    _flag_names("--bins") + ("bins",))
cli("simulate.--bin-width=tiny", _SIM + ["--bin-width", "1e-12"], "error",
    _flag_names("--bin-width"))
cli("simulate.--bin-width=huge", _SIM + ["--bin-width", "1e300"], "ok", check=_wrote("r.npz"))
cli("simulate.--segments=huge", _SIM + ["--model", "mesh", "--segments", "100000000"], "error",
    _flag_names("--segments"))
cli("simulate.--ray-spacing=tiny", _MESH + ["--ray-spacing", "1e-9"], "error",
    _flag_names("--ray-spacing"), setup=_SPHERE_FILE)
cli("simulate.--ray-spacing=huge", _MESH + ["--ray-spacing", "1e300"], "error",
    _flag_names("--ray-spacing") + ("ray_spacing",), setup=_SPHERE_FILE)
cli("simulate.--ray-spacing=wide", _MESH + ["--ray-spacing", "1e3"], "warn",
    setup=_SPHERE_FILE, check=_wrote("r.npz"))
cli("simulate.--rays-per-bin=huge", _MESH + ["--rays-per-bin", "1e300"], "error",
    _flag_names("--rays-per-bin") + ("ray_spacing",), setup=_SPHERE_FILE)
cli("simulate.--tol=1", _MESH + ["--tol", "1"], "error", _flag_names("--tol"),
    setup=_SPHERE_FILE)
cli("simulate.--tol=2", _MESH + ["--tol", "2"], "error", _flag_names("--tol"),
    setup=_SPHERE_FILE)
cli("simulate.--max-rays=0.5", _MESH + ["--tol", "0.5", "--max-rays", "0.5"], "error",
    _flag_names("--max-rays"), setup=_SPHERE_FILE)
cli("simulate.--pixel-size=huge", _SIM + ["--model", "pixel", "--pixel-size", "1e9"],
    "error", _flag_names("--pixel-size"))
cli("simulate.--pixel-size=tiny", _SIM + ["--model", "pixel", "--pixel-size", "1e-9"],
    "error", _flag_names("--pixel-size"))
cli("simulate.--jobs=huge", _MESH + ["--jobs", "100000"], "error", _flag_names("--jobs"),
    setup=_SPHERE_FILE, precheck=_refuses_many_jobs)
cli("simulate.--receiver=opposite", _MESH + ["--receiver=-1,0,0"], "error",
    _flag_names("--receiver"), setup=_SPHERE_FILE)
cli("simulate.--z0=outside-warns", _MESH + ["--mode", "slice", "--z0", "5"], "warn",
    setup=_SPHERE_FILE, check=_wrote("r.npz"))
cli("simulate.--seed=huge", _MESH + ["--seed", "1" + "0" * 30], "ok", setup=_SPHERE_FILE,
    check=_wrote("r.npz"))

# options that do not apply, or clash
cli("simulate.--views+--angles-deg", _SIM + ["--angles-deg", "0,90"], "error",
    ("--views", "--angles-deg"))
cli("simulate.analytic+--jobs", _SIM + ["--jobs", "2"], "ok", check=_wrote("r.npz"))
cli("simulate.analytic+--mode", _SIM + ["--mode", "3d"], "error", "--mode")
cli("simulate.analytic+--backend", _SIM + ["--backend", "packets"], "error", "--backend")
cli("simulate.--backend=optix", _MESH + ["--backend", "optix"], "error", "--backend",
    setup=_SPHERE_FILE)
cli("simulate.--backend=embreex", _MESH + ["--backend", "embreex"], "ok", setup=_SPHERE_FILE,
    check=_wrote("r.npz"))
cli("simulate.analytic+--pixel-size", _SIM + ["--pixel-size", "0.01"], "error",
    "--pixel-size")
cli("simulate.analytic+--scheduler", _SIM + ["--scheduler", "nonsense"], "error",
    ("--scheduler", "scheduler"))
cli("simulate.analytic+--view-vectors", _SIM[:-2] + ["--view-vectors", "10"], "error",
    ("--view-vectors", "view"))
cli("simulate.mesh+--segments", _MESH + ["--segments", "64"], "error", "--segments",
    setup=_SPHERE_FILE)
cli("simulate.--seed+regular", _MESH + ["--seed", "1", "--sampling", "regular"], "error",
    "--seed", setup=_SPHERE_FILE)
cli("simulate.--z0+3d", _MESH + ["--z0", "0.1", "--mode", "3d"], "error", "--z0",
    setup=_SPHERE_FILE)
cli("simulate.--max-rays-without-tol", _MESH + ["--max-rays", "1e6"], "error", "--max-rays",
    setup=_SPHERE_FILE)
cli("simulate.--jobs+--workers", _MESH + ["--jobs", "1", "--workers", "2"], "error",
    ("--jobs", "--workers"), setup=_SPHERE_FILE)
cli("simulate.--receiver+--footprint", _MESH + ["--receiver", "0,1,1", "--footprint"],
    "error", ("--footprint", "footprint"), setup=_SPHERE_FILE)
cli("simulate.--tol+--run-dir", _MESH + ["--tol", "0.5", "--run-dir", "{tmp}/run"], "error",
    ("--tol", "run_dir", "--run-dir"), setup=_SPHERE_FILE)
cli("simulate.--tol+--ray-spacing", _MESH + ["--tol", "0.5", "--ray-spacing", "0.1"], "error",
    ("--tol", "tol"), setup=_SPHERE_FILE)

# coatings
for _key, _v in {"no-equals": "small", "unknown-coating": "small=unobtainium",
                 "unknown-shape": "nope=dark_gray", "empty-name": "=dark_gray"}.items():
    cli(f"simulate.--coating={_key}", ["simulate", "disk_pair", "-o", "{tmp}/r.npz", "--quiet",
                                       "--views", "4", "--coating", _v], "error",
        ("--coating", "coating", "small", "nope", "unobtainium", "''"))
cli("simulate.--material-of-phantom", _SIM + ["--material", "aluminum"], "error", "--material")
cli("simulate.--material=unknown", _MESH + ["--material", "unobtainium"], "error",
    "unobtainium", setup=_SPHERE_FILE)
cli("simulate.--coating=unknown-part", _MESH + ["--coating", "nope=aluminum"], "error",
    "nope", setup=_SPHERE_FILE)
_file_cases("simulate.--materials", "cli", lambda p: _SIM + ["--materials", p], ".toml",
            {k: BAD_TOML[k] for k in ("missing", "dir", "junk", "not-utf8", "deep")},
            ("bad.toml",))
cli("simulate.--materials=valid", ["simulate", "disk_pair", "-o", "{tmp}/r.npz", "--quiet",
                                   "--views", "4", "--materials", "{tmp}/t.toml",
                                   "--coating", "small=mine"], "ok",
    setup=files({"t.toml": TABLE}), check=_wrote("r.npz"))

# ------------------------------------------------------------------ simulate: the scene
cli("simulate.scene=unknown", ["simulate", "nope", "-o", "{tmp}/r.npz"], "error", "nope")
_file_cases("simulate.spec", "cli", lambda p: ["simulate", p, "-o", "{tmp}/r.npz", "--quiet"],
            ".toml", dict(BAD_TOML, **{"long-int": LONG_INT_TOML,
                                       "radius-nan": _spec(radius="nan"),
                                       "overlap": DISK_SPEC
                                       + DISK_SPEC[DISK_SPEC.index(b"[[shape]]"):]}),
            ("bad.toml",))
_file_cases("simulate.mesh-file.stl", "cli",
            lambda p: ["simulate", p, "-o", "{tmp}/r.npz", "--quiet", "--views", "2"], ".stl",
            {"missing": None, "dir": DIR, "empty": b"", "junk": JUNK,
             "truncated": _truncated_stl}, ("bad.stl",))
_file_cases("simulate.mesh-file.obj", "cli",
            lambda p: ["simulate", p, "-o", "{tmp}/r.npz", "--quiet", "--views", "2"], ".obj",
            {"junk": JUNK, "not-utf8": NOT_UTF8_OBJ, "text": b"hello world\n"}, ("bad.obj",))
_file_cases("simulate.mesh-file", "cli",
            lambda p: ["simulate", p, "-o", "{tmp}/r.npz", "--quiet", "--views", "2",
                       "--bins", "8"], ".dat", {"binary-stl": _stl}, (), expect="ok",
            check=_wrote("r.npz"))
_file_cases("simulate.mesh-file", "cli",
            lambda p: ["simulate", p, "-o", "{tmp}/r.npz", "--quiet"], ".npz",
            {"result": _result}, ("bad.npz",))
cli("simulate.spec=valid", ["simulate", "{tmp}/s.toml", "-o", "{tmp}/r.npz", "--quiet"], "ok",
    setup=files({"s.toml": DISK_SPEC}), check=_wrote("r.npz"))
cli("simulate.mesh", _MESH, "ok", setup=_SPHERE_FILE, check=_wrote("r.npz"))
cli("simulate.phantom-as-mesh", _SIM + ["--model", "mesh", "--segments", "64", "--bins", "8"],
    "ok", check=_wrote("r.npz"))
cli("simulate.pixel", _SIM + ["--model", "pixel", "--bins", "16"], "ok", check=_wrote("r.npz"))

# ------------------------------------------------------------------ simulate: the output
cli("simulate.-o=empty", ["simulate", "disk", "-o", "", "--quiet"], "error", "-o")
cli("simulate.-o=dir", ["simulate", "disk", "-o", "{tmp}", "--quiet"], "error", "-o")
cli("simulate.-o=dot", ["simulate", "disk", "-o", ".", "--quiet"], "error", "-o")
cli("simulate.-o=txt", ["simulate", "disk", "-o", "{tmp}/r.txt", "--quiet"], "error", "-o")
cli("simulate.-o=no-suffix", ["simulate", "disk", "-o", "{tmp}/r", "--quiet"], "error", "-o")
cli("simulate.-o=input", ["simulate", "{tmp}/s.toml", "-o", "{tmp}/s.toml", "--quiet"],
    "error", "s.toml", setup=files({"s.toml": DISK_SPEC}))
cli("simulate.-o=input-mesh", ["simulate", "{tmp}/m.npz", "-o", "{tmp}/m.npz", "--quiet"],
    "error", "m.npz", setup=files({"m.npz": _result}))
cli("simulate.-o=--materials", ["simulate", "disk", "-o", "{tmp}/t.npz", "--materials",
                                "{tmp}/t.npz"], "error", "t.npz",
    setup=files({"t.npz": TABLE}))
cli("simulate.-o=--run-dir", _MESH + ["--run-dir", "{tmp}/r.npz"], "error", "r.npz",
    setup=_SPHERE_FILE)
cli("simulate.--run-dir=file", _MESH + ["--run-dir", "{tmp}/f.txt"], "error", "f.txt",
    setup=files({"sphere.stl": _stl, "f.txt": b"x"}))
cli("simulate.--run-dir=empty", _MESH + ["--run-dir", ""], "error", ("--run-dir", "run_dir"),
    setup=_SPHERE_FILE)
cli("simulate.-o=missing-folder", ["simulate", "disk", "-o", "{tmp}/new/sub/r.npz", "--quiet",
                                   "--views", "4"], "ok", check=_wrote("new/sub/r.npz"))
cli("simulate.-o=read-only", ["simulate", "disk", "-o", "{tmp}/ro/r.npz", "--quiet"], "error",
    "/ro", setup=files({"ro": _read_only}), skip_root=True)
cli("simulate.-o=under-a-file", ["simulate", "disk", "-o", "{tmp}/f.txt/r.npz", "--quiet"],
    "error", "f.txt", setup=files({"f.txt": b"x"}))

# ------------------------------------------------------------------ sensor and receive
for _flag in ("--standoff", "--beam-waist", "--pulse-energy", "--aperture", "--wavelength",
              "--flood-radius"):
    for _key in _FEW:
        cli(f"simulate.{_flag}={_key}", _MESH + [_flag, _POS_BAD[_key]], "error", _flag,
            setup=_SPHERE_FILE)
for _flag in ("--extinction", "--beam-divergence"):
    cli(f"simulate.{_flag}=neg", _MESH + [_flag, "-1"], "error", _flag, setup=_SPHERE_FILE)
for _key, _v in {"one": "1", "nan": "nan,0", "str": "x,y"}.items():
    cli(f"simulate.--beam-offset={_key}", _MESH + ["--beam-offset", _v], "error",
        "--beam-offset", setup=_SPHERE_FILE)
cli("simulate.--standoff+analytic", _SIM + ["--standoff", "10"], "error", "--standoff")
cli("simulate.--standoff+slice", _MESH + ["--standoff", "10", "--mode", "slice"], "error",
    "--mode 3d", setup=_SPHERE_FILE)
cli("simulate.--standoff=inside", _MESH + ["--standoff", "0.1"], "error", "inside the target",
    setup=_SPHERE_FILE)
cli("simulate.--beam-divergence-alone", _MESH + ["--beam-divergence", "0.1"], "error",
    "--beam-waist", setup=_SPHERE_FILE)
cli("simulate.--pulse-energy+paper", _MESH + ["--standoff", "50", "--pulse-energy", "1e-3",
                                             "--aperture", "0.1"], "error", "radiometry",
    setup=_SPHERE_FILE)
cli("simulate.--radiometry=x", _SIM + ["--radiometry", "x"], "error", "--radiometry")
_RECV = ["receive", "{tmp}/r.npz", "-o", "{tmp}/w.npz", "--quiet", "--sample-rate", "1e10"]
_file_cases("receive.result", "cli", lambda p: ["receive", p, "-o", "{tmp}/w.npz", "--quiet",
                                                "--sample-rate", "1e10"], ".npz",
            {"missing": None, "dir": DIR, "empty": b"", "junk": JUNK,
             "pickled": _pickled_result, "image": _image_result}, ("bad.npz",))
cli("receive.ok", _RECV, "ok", setup=_RESULT_FILE, check=_wrote("w.npz"))
for _flag in ("--sample-rate", "--pulse-fwhm", "--realisations", "--speckle-cells"):
    for _key in _FEW:
        cli(f"receive.{_flag}={_key}", _RECV + [_flag, _POS_BAD[_key]], "error", _flag,
            setup=_RESULT_FILE)
cli("receive.--sample-rate=huge", _RECV + ["--sample-rate", "1e18"], "error",
    "--sample-rate", setup=_RESULT_FILE)
cli("receive.noise-on-relative-units", _RECV + ["--realisations", "2"], "error",
    "photoelectrons", setup=_RESULT_FILE)
cli("receive.--gain-without-realisations", _RECV + ["--gain", "2"], "error", "--realisations",
    setup=_RESULT_FILE)
cli("receive.--speckle-cells=0.5", _RECV + ["--scale", "10", "--realisations", "2",
                                           "--speckle-cells", "0.5"], "error", "--speckle-cells",
    setup=_RESULT_FILE)
cli("receive.-o=input", ["receive", "{tmp}/r.npz", "-o", "{tmp}/r.npz", "--sample-rate",
                         "1e10"], "error", "input", setup=_RESULT_FILE)
cli("receive.--plot=input", _RECV + ["--plot", "{tmp}/r.npz"], "error", "--plot",
    setup=_RESULT_FILE)

# ------------------------------------------------------------------ reconstruct
_file_cases("reconstruct.result", "cli", lambda p: ["reconstruct", p, "-o", "{tmp}/r.png",
                                                    "--quiet", "--size", "16"], ".npz",
            {"missing": None, "dir": DIR, "empty": b"", "junk": JUNK,
             "truncated": _truncated_result, "text": b"hello\n", "not-utf8": NOT_UTF8_TOML,
             "no-meta": _no_meta_result, "pickled": _pickled_result,
             "deep-meta": _deep_meta_result, "image": _image_result}, ("bad.npz",))
_file_cases("reconstruct.result", "cli", lambda p: ["reconstruct", p, "-o", "{tmp}/r.png",
                                                    "--quiet", "--size", "16"], ".dat",
            {"valid": _result}, (), expect="ok", check=_wrote("r.png"))
for _key, _v in {"zero": "0", "neg": "-1", "str": "x", "float": "1.5", "empty": ""}.items():
    cli(f"reconstruct.--size={_key}", _REC[:-1] + [_v], "error", "--size", setup=_RESULT_FILE)
cli("reconstruct.--size=huge", _REC[:-1] + ["100000"], "error", _flag_names("--size"),
    setup=_RESULT_FILE)
for _flag in ("--extent", "--clip"):
    for _key, _v in {"zero": "0", "neg": "-1", "nan": "nan", "inf": "inf", "str": "x"}.items():
        cli(f"reconstruct.{_flag}={_key}", _REC + [_flag, _v], "error", _flag,
            setup=_RESULT_FILE)
cli("reconstruct.--clip=2", _REC + ["--clip", "2"], "error", ("--clip",),
    setup=_RESULT_FILE)
cli("reconstruct.--extent=huge", _REC + ["--extent", "1e300"], "ok", setup=_RESULT_FILE,
    check=_wrote("r.png"))
cli("reconstruct.--filter=x", _REC + ["--filter", "x"], "error", "--filter",
    setup=_RESULT_FILE)
cli("reconstruct.-o=empty", ["reconstruct", "{tmp}/r.npz", "-o", ""], "error", "-o",
    setup=_RESULT_FILE)
cli("reconstruct.-o=dir", ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}"], "error", "-o",
    setup=_RESULT_FILE)
cli("reconstruct.-o=txt", ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}/r.txt"], "error", "-o",
    setup=_RESULT_FILE)
cli("reconstruct.-o=npz", ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}/x.npz", "--quiet",
                          "--size", "16"], "ok", setup=_RESULT_FILE,
    check=lambda tmp: _wrote("x.npz")(tmp) and not (tmp / "x.image.npz").exists())
cli("reconstruct.-o=input", ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}/r.npz"], "error",
    "r.npz", setup=_RESULT_FILE)
cli("reconstruct.-o=image-data-is-input", ["reconstruct", "{tmp}/r.image.npz", "-o",
                                           "{tmp}/r.png"], "error", "r.image.npz",
    setup=files({"r.image.npz": _result}))
cli("reconstruct.-o=missing-folder", ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}/a/b/r.png",
                                      "--quiet", "--size", "16"], "ok", setup=_RESULT_FILE,
    check=_wrote("a/b/r.png"))
cli("reconstruct.-o=read-only", ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}/ro/r.png",
                                 "--size", "16"], "error", "/ro",
    setup=files({"r.npz": _result, "ro": _read_only}), skip_root=True)
cli("reconstruct.-o=under-a-file", ["reconstruct", "{tmp}/r.npz", "-o", "{tmp}/f.txt/r.png",
                                    "--size", "16"], "error", "f.txt",
    setup=files({"r.npz": _result, "f.txt": b"x"}))
cli("reconstruct.no-output", ["reconstruct", "{tmp}/r.npz"], "error", "-o",
    setup=_RESULT_FILE)
cli("reconstruct.log+clip", _REC + ["--log", "--clip", "0.5"], "ok", setup=_RESULT_FILE,
    check=_wrote("r.image.npz"))

# ------------------------------------------------------------------ view (bad arguments only)
_VIEW = ["view", "disk", "--screenshot", "{tmp}/v.png", "--quiet"]
for _key, _v in {"nan": "nan", "inf": "inf", "-inf": "-inf", "str": "x", "empty": ""}.items():
    cli(f"view.--view-angle={_key}", _VIEW + [f"--view-angle={_v}"], "error", "--view-angle")
cli("view.--screenshot=empty", ["view", "disk", "--screenshot", ""], "error", "--screenshot")
cli("view.--screenshot=dir", ["view", "disk", "--screenshot", "{tmp}"], "error",
    "--screenshot")
cli("view.--screenshot=jpg", ["view", "disk", "--screenshot", "{tmp}/v.jpg"], "error",
    "--screenshot")
cli("view.--screenshot=input", ["view", "{tmp}/s.png", "--screenshot", "{tmp}/s.png"],
    "error", "--screenshot", setup=files({"s.png": _stl}))
cli("view.no-display", ["view", "disk"], "error", "--screenshot")
cli("view.scene=unknown", ["view", "nope", "--screenshot", "{tmp}/v.png"], "error", "nope")
cli("view.--material-of-phantom", _VIEW + ["--material", "aluminum"], "error", "--material")
cli("view.--coating=unknown", _VIEW + ["--coating", "d=unobtainium"], "error",
    "unobtainium")
_file_cases("view.spec", "cli", lambda p: ["view", p, "--screenshot", "{tmp}/v.png"], ".toml",
            {k: BAD_TOML[k] for k in ("missing", "empty", "junk", "deep")}, ("bad.toml",))
_file_cases("view.mesh-file", "cli", lambda p: ["view", p, "--screenshot", "{tmp}/v.png"],
            ".stl", {"empty": b"", "junk": JUNK, "truncated": _truncated_stl}, ("bad.stl",))
_file_cases("view.--materials", "cli", lambda p: _VIEW + ["--materials", p], ".toml",
            {"junk": JUNK, "not-utf8": NOT_UTF8_TOML, "deep": DEEP_TOML}, ("bad.toml",))

# ------------------------------------------------------------------ bounces, lrcs (issue 33)
for _key, _v in {"zero": "0", "nine": "9", "float": "2.5", "word": "two"}.items():
    cli(f"simulate.--bounces={_key}", _MESH + ["--radiometry", "power", "--bounces", _v],
        "error", _flag_names("--bounces"), setup=_SPHERE_FILE)
    cli(f"lrcs.--bounces={_key}", ["lrcs", "{tmp}/sphere.stl", "--views", "2", "--bounces",
                                   _v], "error", _flag_names("--bounces"),
        setup=_SPHERE_FILE)
for _key, _v in {"zero": "0", "float": "1e3", "huge": str(1 << 30)}.items():
    cli(f"simulate.--bounce-samples={_key}", _MESH + ["--bounces", "2", "--bounce-samples",
                                                      _v],
        "error", _flag_names("--bounce-samples"), setup=_SPHERE_FILE)
for _key, _v in {"zero": "0", "neg": "-3", "word": "many"}.items():
    cli(f"lrcs.--views={_key}", ["lrcs", "{tmp}/sphere.stl", "--views", _v], "error",
        _flag_names("--views"), setup=_SPHERE_FILE)
cli("lrcs.views-and-angles", ["lrcs", "{tmp}/sphere.stl", "--views", "2", "--angles-deg",
                              "0,90"], "error", ("--views", "--angles-deg"),
    setup=_SPHERE_FILE)
