"""Peer validation of the received-power radiometry (``radiometry="power"``) against an
independent renderer, Mitsuba 3 + mitransient (:mod:`meshladar.studies.peer`), and against exact
references: the closed form for a Lambertian sphere and the exact bin integrals of the same
faceted mesh.

Needs ``pip install mitsuba==3.9.1 mitransient==1.3.1 drjit==1.5.0`` and, on Debian 12,
``apt-get install libllvm19``. Without them the renderer tests skip, except under CI
(environment variable CI set), where they fail: a peer check that silently skips in CI
checks nothing.
"""

from __future__ import annotations

import glob
import os
import subprocess
import sys

import numpy as np
import pytest

import meshladar as ml
from meshladar.studies import peer
from meshladar.materials import lambertian

#: meshladar against mitransient, relative L2 over the profile (the brief's bar). Both see
#: the same mesh, so faceting cancels and only sampling noise remains: measured 3.2e-4 to
#: 4.0e-4 at these budgets (seeds 0-3; meshladar 1.2e-4 to 1.6e-4 at 16M rays, mitransient
#: 3.0e-4 to 3.6e-4 at 100 spp on 256x256 pixels), a 2.5x margin.
PEER_TOL = 1e-3

#: Either tool against the exact profile of the same faceted mesh: its sampling error
#: alone (the largest measured is 3.6e-4, mitransient's), with some margin.
SAMPLING_TOL = 7e-4

#: Either tool against the closed form for the true sphere: the faceting error of the
#: 81,920-face icosphere (8.05e-4, computed exactly by convex_power_profile and asserted
#: below) plus the sampling error above.
CLOSED_FORM_TOL = 8.05e-4 + SAMPLING_TOL

#: The off-centre, small-mesh check of the path-length mapping: a 5,120-face sphere at low
#: budgets (measured 1.6e-3 and 3.0e-3); a range offset of a twentieth of a bin already
#: gives about 1e-2.
MAPPING_TOL = 1e-2

RHO = 0.5
VIEW = np.array([0.3, 0.5, 0.8]) / np.linalg.norm([0.3, 0.5, 0.8])
#: Subdivision 6: 81,920 faces, tens of thousands as the brief asks; mitransient renders it
#: in 1-3 s at 100 spp on 256x256 pixels on 2 cores.
SUBDIVISIONS = 6
N_BINS = 64


def _rel(a, b):
    return float(np.linalg.norm(np.asarray(a) - b) / np.linalg.norm(b))


def _meshladar_power(mesh, view, edges, rho, spacing, seed=0):
    scene = ml.Scene.from_mesh(mesh, lambertian(rho))
    ladar = ml.Ladar(None, edges, view_vectors=np.asarray(view)[None])
    sino = ml.simulate(scene, ladar, model="mesh", radiometry="power", normals="flat",
                       ray_spacing=spacing, seed=seed)
    assert sino.info["radiometry"] == "power"
    return sino.values[0]


@pytest.fixture(scope="module")
def sphere(renderer):
    """A unit Lambertian icosphere at the origin, its top at range −1, bins over [−1, 0]
    (the visible half): both tools' profiles and both references."""
    import trimesh

    mesh = trimesh.creation.icosphere(subdivisions=SUBDIVISIONS, radius=1.0)
    v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    edges = np.linspace(-1.0, 0.0, N_BINS + 1)
    mt, info = peer.mitransient_profile(v, f, VIEW, edges, reflectance=RHO, spp=100,
                                        film=(256, 256), seed=0)
    return {"faces": len(f), "edges": edges, "info": info, "mitransient": mt,
            "meshladar": _meshladar_power(mesh, VIEW, edges, RHO, 5e-4),
            "exact": peer.convex_power_profile(v, f, VIEW, edges, RHO),
            "closed": peer.sphere_power_profile(edges, 1.0, RHO, -1.0)}


@pytest.mark.slow
def test_meshladar_and_mitransient_agree_on_a_lambertian_sphere(sphere):
    assert sphere["faces"] == 81920
    assert sphere["info"]["variant"] == "llvm_ad_mono" and sphere["info"]["spp"] == 100
    assert _rel(sphere["meshladar"], sphere["mitransient"]) < PEER_TOL
    # the totals (the whole visible half is inside the bins) are far less noisy than the
    # bins: measured within 3e-6 of each other and of the exact total
    assert sphere["meshladar"].sum() == pytest.approx(sphere["exact"].sum(), rel=3e-5)
    assert sphere["mitransient"].sum() == pytest.approx(sphere["exact"].sum(), rel=3e-5)


@pytest.mark.slow
def test_both_tools_match_the_exact_profile_of_the_faceted_mesh(sphere):
    assert _rel(sphere["meshladar"], sphere["exact"]) < SAMPLING_TOL
    assert _rel(sphere["mitransient"], sphere["exact"]) < SAMPLING_TOL


@pytest.mark.slow
def test_both_tools_match_the_closed_form_for_a_lambertian_sphere(sphere):
    # P(d) = (ρ/π) cos²θ · 2πR with cos θ = 1 − d/R: 2ρR(1 − d/R)², total 2ρR²/3
    closed = sphere["closed"]
    assert closed.sum() == pytest.approx(2 * RHO / 3, rel=1e-12)
    assert _rel(sphere["exact"], closed) == pytest.approx(8.05e-4, abs=1e-5)
    assert _rel(sphere["meshladar"], closed) < CLOSED_FORM_TOL
    assert _rel(sphere["mitransient"], closed) < CLOSED_FORM_TOL


def test_the_facet_reference_converges_to_the_closed_form_at_second_order():
    # no renderer needed: the faceting error falls 4x per subdivision (edge length halves)
    import trimesh

    edges = np.linspace(-1.0, 0.0, N_BINS + 1)
    closed = peer.sphere_power_profile(edges, 1.0, RHO, -1.0)
    errs = []
    for s in (3, 4, 5):
        m = trimesh.creation.icosphere(subdivisions=s, radius=1.0)
        errs.append(_rel(peer.convex_power_profile(m.vertices, m.faces, VIEW, edges, RHO),
                         closed))
    assert 3.0 < errs[0] / errs[1] < 5.0 and 3.0 < errs[1] / errs[2] < 5.0


def test_the_path_length_mapping_holds_off_centre_and_on_an_oblong_film(renderer):
    # a small sphere away from the origin, bins starting before its top: empty bins stay
    # empty and the rest falls where the exact profile puts it
    import trimesh

    radius, centre, rho = 0.3, np.array([2.0, -1.0, 0.5]), 0.8
    mesh = trimesh.creation.icosphere(subdivisions=4, radius=radius)
    mesh.apply_translation(centre)
    w = np.array([-0.6, 0.2, -0.77]) / np.linalg.norm([-0.6, 0.2, -0.77])
    top = -float(centre @ w) - radius
    edges = top + np.linspace(-0.05, 0.35, 41)
    exact = peer.convex_power_profile(mesh.vertices, mesh.faces, w, edges, rho)
    assert not exact[:5].any()
    for film in ((128, 128), (128, 96)):
        mt, info = peer.mitransient_profile(mesh.vertices, mesh.faces, w, edges,
                                            reflectance=rho, spp=16, film=film, seed=1)
        assert not mt[:5].any()
        assert _rel(mt, exact) < MAPPING_TOL
        assert info["mapping"]["bin_width_opl"] == pytest.approx(0.01)
    assert _rel(_meshladar_power(mesh, w, edges, rho, 2e-3), exact) < MAPPING_TOL


def test_uneven_bins_are_refused_before_mitsuba_is_loaded():
    with pytest.raises(ValueError, match="evenly spaced"):
        peer.mitransient_profile(np.eye(3), [[0, 1, 2]], (0, 0, 1), [0.0, 0.1, 0.3])


def test_importing_meshladar_and_its_peer_module_loads_no_renderer():
    code = ("import sys, meshladar, meshladar.studies.peer; "
            "print([m for m in ('mitsuba', 'drjit', 'mitransient') if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=120).stdout
    assert out.strip() == "[]"


#: libLLVM files drjit 1.5 cannot use: a missing one (drjit raises) and, where Debian 12's
#: LLVM 15 is installed, that one (drjit's kernel compilation aborts the process: SIGABRT).
_BAD_LLVM = ["/nonexistent/libLLVM.so"] + sorted(glob.glob("/usr/lib/*-linux-gnu/libLLVM-15.so.1"))


@pytest.mark.slow
@pytest.mark.parametrize("libllvm", _BAD_LLVM)
def test_available_says_no_instead_of_crashing_with_an_unusable_libllvm(libllvm):
    # the probe runs in a child process, so neither a raise nor an abort reaches the caller
    code = "from meshladar.studies import peer; print(peer.available(reason=True))"
    env = dict(os.environ, DRJIT_LIBLLVM_PATH=libllvm)
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, timeout=400)
    assert res.returncode == 0, res.stderr
    assert res.stdout.startswith("(False, ")
