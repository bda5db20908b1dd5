"""The command line as a user drives it: round trips, pictures, and one-line errors."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import meshladar as ml
from meshladar.cli import main
from meshladar import io as results

SUBCOMMANDS = ["demo", "materials", "paper", "simulate", "reconstruct", "view", "study",
               "bench"]


def _cli(*args, cwd=None, check=False):
    return subprocess.run([sys.executable, "-m", "meshladar", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd, check=check, timeout=600)


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:.* views are too few")   # 36 views: a quick round trip
def test_simulate_then_reconstruct_round_trip(tmp_path):
    res = _cli("simulate", "disk_pair", "-o", tmp_path / "pair.npz", "--coating",
               "small=aluminum", "--views", "36", check=True)
    assert "wrote" in res.stdout
    sino, meta = results.load_sinogram(tmp_path / "pair.npz")
    pair = ml.phantoms.load("disk_pair", materials={"small": "aluminum"})
    ladar = ml.Ladar(np.arange(36) * 10.0, pair.ladar.bin_edges)
    np.testing.assert_array_equal(sino.values, ml.simulate(pair.scene, ladar).values)
    assert meta["scene"]["shapes"][1]["material"]["name"] == "aluminum"
    assert meta["params"]["model"] == "analytic" and meta["meshladar_version"]
    _cli("reconstruct", tmp_path / "pair.npz", "-o", tmp_path / "pair.png", "--size", "64",
         check=True)
    img_arrays, img_meta = results.load_result(str(tmp_path / "pair.png")[:-4] + ".image.npz")
    expected = ml.fbp(sino, size=64, extent=0.8)
    np.testing.assert_allclose(img_arrays["image"], expected.values, rtol=1e-12, atol=1e-12)
    assert (tmp_path / "pair.png").stat().st_size > 1000


@pytest.mark.slow
def test_simulate_a_mesh_file_with_two_coatings(tmp_path):
    import trimesh

    sc = trimesh.Scene()
    sc.add_geometry(trimesh.creation.box(extents=(0.3, 0.3, 0.3)), node_name="body",
                    transform=trimesh.transformations.translation_matrix([-0.3, 0, 0]))
    sc.add_geometry(trimesh.creation.icosphere(subdivisions=2, radius=0.15),
                    node_name="dome",
                    transform=trimesh.transformations.translation_matrix([0.3, 0, 0]))
    sc.export(tmp_path / "obj.glb")
    _cli("simulate", tmp_path / "obj.glb", "--material", "dark_gray", "--coating",
         "dome=aluminum", "--views", "12", "--bins", "128", "--bin-width", "0.01", "-o",
         tmp_path / "obj.npz", "--quiet", check=True)
    sino, meta = results.load_sinogram(tmp_path / "obj.npz")
    assert sino.shape == (12, 128) and sino.model == "mesh"
    names = {m["name"] for m in meta["scene"]["materials"]}
    assert names == {"dark_gray", "aluminum"}


@pytest.mark.slow
def test_view_writes_a_screenshot(tmp_path):
    from _rendering import _SMOKE

    if subprocess.run([sys.executable, "-c", _SMOKE], capture_output=True).returncode:
        pytest.skip("off-screen rendering unavailable (see _rendering)")
    _cli("view", "disk_pair", "--view-angle", "0", "--screenshot", tmp_path / "v.png",
         check=True)
    import matplotlib.image as mpimg

    img = mpimg.imread(tmp_path / "v.png")
    assert img.shape[0] > 100 and img[..., :3].std() > 0.05
    # at a chosen size, from the ladar's view
    _cli("view", "disk_pair", "--size", "320x200", "--camera", "view", "--screenshot",
         tmp_path / "s.png", check=True)
    assert mpimg.imread(tmp_path / "s.png").shape[:2] == (200, 320)
    res = _cli("view", "disk_pair", "--size", "320by200", "--screenshot", tmp_path / "t.png")
    assert res.returncode == 2 and "--size" in res.stderr and "WIDTHxHEIGHT" in res.stderr
    assert not (tmp_path / "t.png").exists()


# one subprocess each (seconds of imports): the fast subset asks one command for its help
@pytest.mark.parametrize("sub", [s if s == "simulate" else pytest.param(s, marks=pytest.mark.slow)
                                 for s in SUBCOMMANDS])
def test_help_everywhere_with_examples(sub):
    res = _cli(sub, "--help", check=True)
    assert "usage: meshladar" in res.stdout and "example" in res.stdout


#: A bad command line and what its one error line says.
BAD_INPUT = [
    (["simulate", "nope", "-o", "x.npz"], "not a known phantom"),
    (["simulate", "missing.stl", "-o", "x.npz"], "no such mesh file"),
    (["simulate", "disk_pair", "--coating", "small=gold", "-o", "x.npz"],
     "unknown coating 'gold'"),
    (["simulate", "disk_pair", "--coating", "huge=aluminum", "-o", "x.npz"],
     "no shape named 'huge'"),
    (["simulate", "disk_pair", "--coating", "small=aluminum,small=dark_gray", "-o", "x.npz"],
     "part 'small' is given two coatings ('aluminum' and 'dark_gray'); give each part one"),
    (["simulate", "disk_pair", "--coating", "small=aluminum", "--coating", "small=dark_gray",
      "-o", "x.npz"],
     "part 'small' is given two coatings ('aluminum' and 'dark_gray'); give each part one"),
    (["simulate", "disk_pair", "--views", "0", "-o", "x.npz"], "must be a positive integer"),
    (["simulate", "disk_pair", "--views", "4", "--angles-deg", "0,1", "-o", "x.npz"],
     "--views and --angles-deg both choose the views"),
    (["simulate", "disk_pair", "--bin-width", "nan", "--bins", "3", "-o", "x.npz"],
     "must be a positive finite number"),
    (["simulate", "bad.obj", "-o", "x.npz"], "vertices must be finite"),
    (["reconstruct", "missing.npz", "-o", "x.png"], "no such result file"),
    (["reconstruct", "junk.npz", "-o", "x.png"], "not a readable result file"),
    (["reconstruct", "plain.npz", "-o", "x.png"], "not a meshladar result"),
    (["materials", "missing.toml"], "cannot read material table"),
    (["view", "nope"], "not a known phantom"),
    (["view", "disk_pair", "--view-angle", "abc"],
     "argument --view-angle: must be a finite number"),
    (["study", "pixels", "out"], "invalid choice"),
    (["paper"], "required: outdir"),
    (["paper", "out", "--size", "-3"], "must be a positive integer"),
    (["bench", "--repeats", "0"], "must be a positive integer"),
    (["demo", "--angles-deg", "1,nan"], "must be finite numbers"),
    (["reconstruct", "junk.npz", "-o", "x.png", "--filter", "rampp"], "invalid choice"),
    (["simulate", "disk_pair", "-o", "x.npz", "--model", "mesh", "--tol", "2"],
     "tol must be in (0, 1)"),
]
#: The ones the fast subset runs (a subprocess each; the matrix's cli cases run every
#: command's bad input in this process): a scene source, a coating given twice, a result
#: file, argparse's own.
FAST_BAD_INPUT = (0, 5, 11, 16)


@pytest.mark.parametrize("args, message", [
    case if i in FAST_BAD_INPUT else pytest.param(*case, marks=pytest.mark.slow)
    for i, case in enumerate(BAD_INPUT)])
def test_bad_input_is_one_clear_line(tmp_path, args, message):
    (tmp_path / "bad.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n")
    (tmp_path / "junk.npz").write_bytes(b"\x00" * 64)
    np.savez(tmp_path / "plain.npz", a=np.zeros(2))
    res = _cli(*args, cwd=tmp_path)
    assert res.returncode == 2, res.stderr
    assert "Traceback" not in res.stderr and message in res.stderr
    assert res.stderr.strip().count("\n") == 0 or "usage:" in res.stderr


def test_the_command_line_and_figures_leave_a_sessions_state_as_it_was(tmp_path):
    import warnings

    import matplotlib

    from meshladar.cli import main

    backend = matplotlib.get_backend()
    matplotlib.rcParams["font.size"] = 13.0
    fmt = warnings.formatwarning
    assert main(["simulate", "disk", "--views", "360", "-o", str(tmp_path / "d.npz"),
                 "--quiet"]) == 0
    assert main(["reconstruct", str(tmp_path / "d.npz"), "-o", str(tmp_path / "d.png"),
                 "--size", "32", "--quiet"]) == 0
    assert (tmp_path / "d.png").stat().st_size > 1000
    # no backend switched, no rcParams or warning format left changed (a notebook's own)
    assert matplotlib.get_backend() == backend
    assert matplotlib.rcParams["font.size"] == 13.0
    assert warnings.formatwarning is fmt
    matplotlib.rcdefaults()


@pytest.mark.parametrize("argv, work", [
    (["paper", "{tmp}/out"], "meshladar.studies.paper:simulate"),
    (["study", "faceting", "{tmp}/s", "--quiet"], "meshladar.studies.faceting:simulate"),
    (["study", "reconstruction", "{tmp}/r"], "meshladar.studies.reconstruction:run"),
    (["study", "tomography3d", "{tmp}/t"], "meshladar.studies.paper:run_3d"),
])
def test_a_plain_install_is_told_before_the_work(argv, work, tmp_path, capsys, monkeypatch):
    # without matplotlib, a command that draws says so at once (it used to compute for
    # 18-93 s first, then fail on the figure, leaving its folder empty)
    import importlib

    module, name = work.split(":")

    def reached(*args, **kwargs):
        raise AssertionError(f"{work} ran before the missing extra was named")

    monkeypatch.setattr(importlib.import_module(module), name, reached)
    monkeypatch.setitem(sys.modules, "matplotlib", None)          # import fails
    code = main([a.replace("{tmp}", str(tmp_path)) for a in argv])
    err = capsys.readouterr().err
    assert code == 2 and err.strip() == ("meshladar: error: figures need matplotlib: pip "
                                         "install 'meshladar[viz]'")
    assert not any(tmp_path.iterdir())                            # nothing half-written


def test_reconstruct_to_npz_writes_the_values_alone_without_matplotlib(tmp_path, capsys,
                                                                       monkeypatch):
    # -o X.npz: the image's (or volume's) values alone in X.npz, no figure, so a plain
    # install reconstructs; an -o naming the input is still refused before the work
    from meshladar.meshes import fibonacci_sphere
    from meshladar.reconstruct.volumes import fbp3d

    monkeypatch.setitem(sys.modules, "matplotlib", None)          # import fails
    scene = ml.Scene([ml.Disk((0.2, -0.1), 0.5, ml.materials.lambertian(0.5))])
    planar = ml.simulate(scene, ml.Ladar.covering(scene, n_bins=64))
    W = fibonacci_sphere(60)
    solid = ml.Sinogram(np.ones((60, 16)), angles_deg=np.degrees(np.arctan2(W[:, 1], W[:, 0])),
                        bin_edges=np.linspace(-1.0, 1.0, 17), view_vectors=W)
    for name, sino, key, api in (("disk", planar, "image", lambda s: ml.fbp(s, size=32)),
                                 ("ball", solid, "values", lambda s: fbp3d(s, size=12))):
        path, out = tmp_path / f"{name}.npz", tmp_path / f"{name}-values.npz"
        results.save_sinogram(path, sino)
        assert main(["reconstruct", str(path), "-o", str(out), "--size",
                     "32" if key == "image" else "12"]) == 0
        assert capsys.readouterr().out.startswith(f"wrote {out} (")
        arrays, meta = results.load_result(out)
        np.testing.assert_allclose(arrays[key], api(sino).values, rtol=0,
                                   atol=1e-12 * np.abs(api(sino).values).max())
        assert meta["kind"] == ("image" if key == "image" else "volume")
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "ball-values.npz", "ball.npz", "disk-values.npz", "disk.npz"]     # no figure
    before = (tmp_path / "disk.npz").read_bytes()
    assert main(["reconstruct", str(tmp_path / "disk.npz"), "-o",
                 str(tmp_path / "disk.npz")]) == 2
    assert (tmp_path / "disk.npz").read_bytes() == before


def test_model_errors_name_the_flags(tmp_path, capsys):
    # the API's own words (model='mesh') are Python; the command line names its flags
    box = tmp_path / "box.stl"
    import trimesh

    trimesh.creation.box(extents=(0.2, 0.2, 0.2)).export(box)
    for argv, expected in (
            (["simulate", str(box), "--model", "analytic", "-o", str(tmp_path / "a.npz")],
             "--model analytic needs a phantom"),
            (["simulate", "disk", "--model", "pixel", "--view-vectors", "10", "-o",
              str(tmp_path / "b.npz")], "--view-vectors places views over the sphere")):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.startswith("meshladar: error: ") and expected in err, err
        assert "model='" not in err and err.count("\n") == 1


@pytest.mark.parametrize("command", ["demo", "materials", "paper", "simulate", "reconstruct",
                                     "receive", "scan", "lrcs", "view", "study", "bench"])
def test_help_describes_a_command_in_prose_without_its_api_sections(command, capsys):
    """A command's description is its docstring's prose: the numpydoc sections that
    document the function for the API reference stay out of ``--help``."""
    from meshladar.cli import COMMANDS, main

    with pytest.raises(SystemExit) as done:
        main([command, "--help"])
    assert done.value.code == 0
    out = capsys.readouterr().out
    first = COMMANDS[command].__doc__.split("\n")[0].strip()
    assert first in out
    assert "----------" not in out and "argparse.Namespace" not in out
    for markup in (":func:", ":class:", ":meth:", ":mod:", ":data:", "``", "`~"):
        assert markup not in out, markup


def test_help_turns_the_docstrings_markup_into_plain_words(capsys):
    """reST roles and literals read as plain text in ``--help`` (they showed as
    ``:func:`meshladar.waveforms.receive```), paragraphs filled again to 88 columns."""
    from meshladar.cli import main
    from meshladar.cli.helptext import description

    def doc():
        """Runs :func:`a.b.run` on ``x``, warns a :class:`~meshladar.errors.MeshladarWarning`
        (:meth:`Ladar.covering <meshladar.ladar.Ladar.covering>`)
        unless ``--quiet``.

        Parameters
        ----------
        args : argparse.Namespace
        """
    assert description(doc) == ("Runs a.b.run() on x, warns a MeshladarWarning "
                                "(Ladar.covering()) unless --quiet.")
    with pytest.raises(SystemExit):
        main(["receive", "--help"])
    out = capsys.readouterr().out
    words = " ".join(out.split())
    assert "The waveforms (meshladar.waveforms.receive()) and any noise" in words
    assert "with --radiometry power warns (a MeshladarWarning) unless --quiet." in words
    prose = out.split("positional arguments")[0]
    assert max(map(len, prose.splitlines())) <= 88
