"""The command line's quick start: a small mesh run (at most QUICK_RAYS rays) is cast with
embreex and weighed in numpy, calling none of numba's compiled loops; on the same hits its
numbers are the compiled loop's to rounding."""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import numpy as np
import pytest

import meshladar as ml
from meshladar import io as results
from meshladar.cli import main
from meshladar.cli.simulate import quick_backend
from meshladar.forward import job
from meshladar.forward.job import QUICK_RAYS, plan_job
from meshladar.forward.mesh import simulate_mesh
from meshladar.meshes import sphere
from meshladar.raytrace import backends
from meshladar.raytrace.plan import plan_trace
from meshladar.weighing.record import Weighing

#: numpy's weighing against the compiled loop's on the same hits: the SR kernel is
#: rearranged there (one square root of three), a few ulps apart
RTOL = 1e-12


@pytest.fixture(scope="module")
def ball():
    return ml.Scene.from_parts([sphere((0.0, 0.0, 0.0), 0.5, 0, subdivisions=4)],
                               [ml.materials.DARK_GRAY])


@pytest.fixture(scope="module")
def ladar(ball):
    return ml.Ladar.covering(ball, n_bins=256, view_vectors=ml.meshes.fibonacci_sphere(2))


def test_small_runs_take_embreex_and_the_rest_stays_as_asked(ball, ladar):
    small = quick_backend(ball, ladar, "mesh", {"ray_spacing": 0.01})
    assert small == {"ray_spacing": 0.01, "backend": "embreex"}
    # 2 views × (1.0 / δ + 2)² rays: above QUICK_RAYS at δ = 1.0 / 800
    big = {"ray_spacing": 1.0 / 800}
    assert 2 * (800 + 2) ** 2 > QUICK_RAYS and quick_backend(ball, ladar, "mesh", big) == big
    for kept in ({"backend": "packets"}, {"tol": 1e-2}, {"bounces": 2}, {"bounces": "auto"}):
        assert quick_backend(ball, ladar, "mesh", kept) == kept
    assert quick_backend(ball, ladar, "analytic", {}) == {}


def test_without_embreex_the_command_line_keeps_auto(ball, ladar, monkeypatch):
    # a platform without embreex's wheel: "auto" stays the packets' choice, never an error
    reference = backends.backend("embreex")
    monkeypatch.setitem(backends.REGISTRY, "embreex", dataclasses.replace(
        reference, available=lambda: (False, "no wheel here")))
    assert quick_backend(ball, ladar, "mesh", {"ray_spacing": 0.01}) == {"ray_spacing": 0.01}


def test_a_small_embreex_run_is_weighed_in_numpy_and_a_big_one_compiled(ball, ladar):
    wg = Weighing(tuple(ball.materials), edges=(ladar.bin_edges,))
    for spacing, stage in ((0.01, "per_hit"), (1.0 / 800, "flat")):
        plan = plan_trace(ball, ladar, backend="embreex", ray_spacing=spacing)
        assert plan_job(plan, wg, ladar.view_vectors).stage.name == stage
    plan = plan_trace(ball, ladar, backend="packets", ray_spacing=0.01)
    assert plan_job(plan, wg, ladar.view_vectors).stage.name == "flat"


@pytest.mark.filterwarnings("ignore::meshladar.errors.LobeSamplingWarning")  # flat facets
@pytest.mark.parametrize("coating", [ml.materials.DARK_GRAY, ml.materials.ALUMINUM])
@pytest.mark.parametrize("options", [{}, {"footprint": True}, {"radiometry": "power"},
                                     {"back_faces": "ignore"}])
def test_numpy_weighing_agrees_with_the_compiled_loop(ball, ladar, coating, options,
                                                      monkeypatch):
    """The same embreex hits weighed in numpy (a small run) and by the compiled loop (the
    same run with QUICK_RAYS at 0)."""
    scene = ml.Scene.from_parts(list(ball.parts), [coating])
    quick = simulate_mesh(scene, ladar, backend="embreex", ray_spacing=0.004, **options)
    monkeypatch.setattr(job, "QUICK_RAYS", 0)
    compiled = simulate_mesh(scene, ladar, backend="embreex", ray_spacing=0.004, **options)
    assert quick.info["rays"] == compiled.info["rays"] > 100_000
    assert quick.values.max() > 0
    np.testing.assert_allclose(quick.values, compiled.values, rtol=RTOL,
                               atol=RTOL * np.abs(compiled.values).max())


def test_the_command_line_says_which_backend_cast(ball, tmp_path, capsys):
    path = tmp_path / "ball.stl"
    _export_stl(ball, path)
    out = tmp_path / "ball.npz"
    assert main(["simulate", str(path), "--material", "dark_gray", "--views", "1", "-o",
                 str(out)]) == 0
    assert "(embreex backend)" in capsys.readouterr().out
    sino, meta = results.load_sinogram(out)
    assert sino.info["backend"] == "embreex" and meta["params"]["model"] == "mesh"


def _export_stl(scene, path):
    import trimesh

    p = scene.parts[0]
    trimesh.Trimesh(p.vertices, p.faces, process=False).export(path)


def test_a_small_command_calls_no_compiled_loop(tmp_path):
    """In a fresh process, a one-view simulate of a small mesh does not even import numba
    (the modules of compiled loops are imported at their first use), where the same
    command given the packets (the compiled loop) loads it and compiles or loads a loop."""
    ball = str(tmp_path / "ball.stl")
    subprocess.run([sys.executable, "-c", "import trimesh; "
                    f"trimesh.creation.icosphere(3).export({ball!r})"], check=True)
    seen = {}
    for backend in ("auto", "packets"):
        result = str(tmp_path / f"{backend}.npz")
        code = (
            "import sys\n"
            "from meshladar.cli import main\n"
            f"assert main(['simulate', {ball!r}, '--material', 'dark_gray', '--views', '1', "
            f"'--backend', {backend!r}, '--quiet', '-o', {result!r}]) == 0\n"
            "if 'numba' not in sys.modules:\n"
            "    print('no numba')\n"
            "else:\n"
            "    from numba.core.dispatcher import Dispatcher\n"
            "    print(sum(bool(v.overloads) for m in list(sys.modules.values())\n"
            "              if getattr(m, '__name__', '').startswith('meshladar')\n"
            "              for v in vars(m).values() if isinstance(v, Dispatcher)))\n")
        seen[backend] = subprocess.run([sys.executable, "-c", code], capture_output=True,
                                       text=True, check=True).stdout.strip()
    assert seen["auto"] == "no numba"
    assert int(seen["packets"]) >= 1
