"""``meshladar lrcs``: the table printed and written, against the closed form of a
Lambertian sphere, and bad input as one line."""

from __future__ import annotations

import sys
import warnings

import numpy as np
import pytest
import trimesh

from meshladar import cli


def _ball(tmp_path):
    path = tmp_path / "ball.stl"
    trimesh.creation.icosphere(5, radius=2.0).export(path)
    return path


def _rows(text):
    lines = [ln for ln in text.splitlines() if ln and not ln.startswith("#")]
    head = lines[0].split(",")
    return head, np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])


def test_a_sphere_table_matches_the_closed_form(tmp_path, capsys):
    """A radius-2 icosphere (5 subdivisions) in a Lambertian coating of albedo 0.5 from a
    user's table (SR, diffuse only, b = 0): σ = (8/3)πρR² to the faceting error (3e-4 at 5 subdivisions), per view,
    printed and in the CSV alike, dBsm = 10 log10 σ."""
    table = tmp_path / "mine.toml"
    table.write_text('[white]\nrho_d = 0.5\nepsilon = 0.0\nb = 0.0\ne = 1.0\n'
                     'lobes = "diffuse"\n')
    out = tmp_path / "sigma.csv"
    code = cli.main(["lrcs", str(_ball(tmp_path)), "--views", "4", "--materials", str(table),
                     "--material", "white", "--per-part", "--ray-spacing", "0.005",
                     "-o", str(out)])
    assert code == 0
    printed = capsys.readouterr().out
    head, rows = _rows(out.read_text())
    assert head == ["angle_deg", "sigma", "dbsm", "sigma_mesh"]
    assert _rows(printed)[1].tolist() == rows.tolist()
    np.testing.assert_allclose(rows[:, 0], [0, 90, 180, 270])
    np.testing.assert_allclose(rows[:, 1], 8 / 3 * np.pi * 0.5 * 4.0, rtol=1e-3)
    np.testing.assert_allclose(rows[:, 2], 10 * np.log10(rows[:, 1]), atol=1e-8)
    np.testing.assert_allclose(rows[:, 3], rows[:, 1], rtol=1e-9)
    assert "unit^2 (the scene's length unit: m^2 and dBsm for metres), 1 bounce" in printed


def test_view_vectors_and_a_phantom(tmp_path, capsys):
    assert cli.main(["lrcs", str(_ball(tmp_path)), "--view-vectors", "3", "--quiet",
                     "-o", str(tmp_path / "s.csv")]) == 0
    head, rows = _rows((tmp_path / "s.csv").read_text())
    assert head[:3] == ["wx", "wy", "wz"] and rows.shape == (3, 5)
    assert cli.main(["lrcs", "disk", "--angles-deg", "0,90"]) == 0
    assert "unit^2 per unit height" in capsys.readouterr().out


def test_a_bad_bounce_count_is_argparses_usage_error(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        cli.main(["lrcs", str(_ball(tmp_path)), "--bounces", "9"])
    assert exit_.value.code == 2
    assert "number of bounces from 1 to 8 or 'auto'; got '9'" in capsys.readouterr().err


@pytest.mark.parametrize("argv, match", [
    (["--views", "2", "--angles-deg", "0"], "give one of --views, --angles-deg"),
    (["-o", "sigma.npz"], "-o"),
])
def test_bad_input_is_one_line(tmp_path, capsys, argv, match):
    code = cli.main(["lrcs", str(_ball(tmp_path))] + argv)
    err = capsys.readouterr().err
    assert code == 2 and match in err and "Traceback" not in err


def test_normals_are_the_apis_and_the_lobe_warning_names_the_flag(tmp_path, capsys):
    """``--normals smooth`` gives the API's ``lrcs(..., normals="smooth")`` numbers (and not
    the flat ones), and the faceting warning it answers speaks of ``--normals smooth``,
    not of ``normals='smooth'`` (lrcs had no such flag: its advice could not be taken)."""
    import meshladar as ml
    from meshladar.forward.lrcs import lrcs
    from meshladar.materials import ALUMINUM

    path = tmp_path / "coarse.stl"
    trimesh.creation.icosphere(2, radius=1.0).export(path)
    args = ["lrcs", str(path), "--material", "aluminum", "--views", "3", "--ray-spacing",
            "0.02"]
    with warnings.catch_warnings():
        warnings.simplefilter("always", ml.errors.LobeSamplingWarning)
        # shown as a plain Python shows it (pytest records warnings instead)
        warnings.showwarning = lambda m, c, f, n, file=None, line=None: sys.stderr.write(
            warnings.formatwarning(m, c, f, n, line))
        assert cli.main(args) == 0
    err = capsys.readouterr().err
    assert "use --normals smooth" in err and "normals='smooth'" not in err, err
    out = tmp_path / "smooth.csv"
    with pytest.warns(ml.errors.MeshladarWarning):     # the lobe's sampling, smooth
        assert cli.main(args + ["--normals", "smooth", "--quiet", "-o", str(out)]) == 0
    _, rows = _rows(out.read_text())
    scene = ml.Scene.from_mesh(str(path), material=ALUMINUM)
    views = np.arange(3) * 120.0
    with pytest.warns(ml.errors.MeshladarWarning):
        smooth = lrcs(scene, views, ray_spacing=0.02, normals="smooth")
        flat = lrcs(scene, views, ray_spacing=0.02)
    np.testing.assert_allclose(rows[:, 1], smooth.values, rtol=1e-9)
    assert np.all(np.abs(rows[:, 1] / flat.values - 1.0) > 1e-3)


def _dihedral(tmp_path):
    path = tmp_path / "dihedral.stl"
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 0.7], [0, 0, 0.7], [0, 1, 0.7], [0, 1, 0]],
                 float)
    trimesh.Trimesh(v, [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]]).export(path)
    return path


def test_sampled_orders_print_their_standard_error(tmp_path, capsys):
    """A user's trial: with --bounces each σ (its orders beyond the first sampled) was
    printed to ten figures and no uncertainty, and the paths could not be raised from the
    command line. Now a sigma_stderr column, the API's CrossSection.stderr, and
    --bounce-samples lowers it (as 1/√N: a quarter of the error at 16 × the paths,
    within the error's own sampling spread)."""
    scene = str(_dihedral(tmp_path))
    argv = ["lrcs", scene, "--material", "lambertian", "--angles-deg", "45", "--bounces",
            "2", "--ray-spacing", "0.01", "--seed", "1", "--quiet"]
    errors = []
    for n in ("4096", "65536"):
        assert cli.main(argv + ["--bounce-samples", n]) == 0
        head, rows = _rows(capsys.readouterr().out)
        assert head == ["angle_deg", "sigma", "sigma_stderr", "dbsm"]
        errors.append(rows[0, 2])
    assert 0 < errors[1] and 3.0 < errors[0] / errors[1] < 5.3


def test_quiet_prints_the_table_unless_it_is_written(tmp_path, capsys):
    """A user's trial: --quiet without -o printed nothing and exited 0 (the table is the
    result). It prints the table alone (no comment line); with -o, nothing."""
    ball = str(_ball(tmp_path))
    assert cli.main(["lrcs", ball, "--angles-deg", "0", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0] == "angle_deg,sigma,dbsm" and len(out.splitlines()) == 2
    assert cli.main(["lrcs", ball, "--angles-deg", "0", "--quiet",
                     "-o", str(tmp_path / "s.csv")]) == 0
    assert capsys.readouterr().out == ""
    assert (tmp_path / "s.csv").read_text() == out


def test_views_raised_above_the_plane_by_elevation(tmp_path, capsys):
    """A user's trial: the command line reached only views in the x-y plane (or N spread
    over the sphere). --elevation-deg raises --angles-deg's views: a Lambertian (ρ = 1)
    plate of area 6 facing x, seen 60° up at azimuth 0, gives 4ρA cos²60° = 6 (by hand);
    the table gives each view's vector."""
    plate = tmp_path / "plate.stl"
    trimesh.Trimesh([[0, -1, 0], [0, 1, 0], [0, 1, 3], [0, -1, 3]],
                    [[0, 1, 2], [0, 2, 3]]).export(plate)
    assert cli.main(["lrcs", str(plate), "--material", "lambertian", "--angles-deg", "0",
                     "--elevation-deg", "60", "--ray-spacing", "0.005", "--quiet"]) == 0
    head, rows = _rows(capsys.readouterr().out)
    assert head == ["wx", "wy", "wz", "sigma", "dbsm"]
    np.testing.assert_allclose(rows[0, :3], [0.5, 0.0, np.sqrt(3) / 2], atol=1e-9)
    assert rows[0, 3] == pytest.approx(4 * 1.0 * 6.0 * 0.25, rel=1e-3)
    with pytest.raises(SystemExit) as parsed:                       # argparse's refusal
        cli.main(["lrcs", str(plate), "--elevation-deg", "100"])
    assert parsed.value.code == 2 and "from -90 to 90" in capsys.readouterr().err
    assert cli.main(["lrcs", str(plate), "--view-vectors", "4", "--elevation-deg", "10"]) == 2
    assert "--view-vectors spreads its own" in capsys.readouterr().err
