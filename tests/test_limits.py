"""Bad input on the newer surfaces (issue 29): sizes bounded before allocating, magnitudes
validated at construction, degenerate input refused, each as one clear ParameterError that
names the argument. Each case was a traceback (MemoryError, OverflowError), a numpy
warning, or a silent zero or NaN image before."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

import meshladar as ml
from meshladar.brdf import Tabulated
from meshladar.errors import ParameterError
from meshladar.fit import coating_kernel, fit_coatings
from meshladar.reconstruct.compensation import compensate
from meshladar.meshes import fibonacci_sphere
from meshladar.reconstruct.iterative import cgls, sirt, tv_fista
from meshladar.sensor import GaussianBeam, Sensor
from meshladar.waveforms import GaussianPulse, SampledPulse, receive


@pytest.fixture(scope="module")
def sino():
    scene = ml.Scene([ml.Disk((0.0, 0.0), 0.6, ml.materials.DARK_GRAY)])
    return ml.simulate(scene, ml.Ladar.paper(angles_deg=np.arange(0.0, 360.0, 10.0)))


CASES = {
    "standoff 1e300": (lambda s: Sensor(standoff=1e300),
                       r"^standoff must be in \(0, 1e\+09\]; got 1e\+300"),
    "pulse energy 1e300": (lambda s: Sensor(standoff=10.0, pulse_energy=1e300,
                                            aperture_diameter=0.1),
                           r"^pulse_energy must be in \(0, 1e\+09\]"),
    "aperture 1e9": (lambda s: Sensor(standoff=10.0, pulse_energy=1.0, aperture_diameter=1e9),
                     r"^aperture_diameter must be in \(0, 1000\]"),
    "wavelength 1e-20": (lambda s: Sensor(wavelength=1e-20),
                         r"^wavelength must be in \[1e-09, 1\]"),
    "waist 1e300": (lambda s: GaussianBeam(1e300), r"^waist must be in \[1e-12, 1e\+09\]"),
    "pulse 1e300 s": (lambda s: GaussianPulse(1e300), r"^fwhm must be in \[1e-18, 1\]"),
    "sampled pulse interval": (lambda s: SampledPulse([1.0], 1e300), r"^interval must be in"),
    "receive standoff 1e308": (lambda s: receive(s, sample_rate=1e9, standoff=1e308),
                               r"^standoff must be in \[0, 1e\+09\]"),
    "receive 810 GiB": (lambda s: receive(s, sample_rate=2e9, pulse=GaussianPulse(1.0)),
                        r"^sample_rate: a pulse 6.79 s long on 6.25e-11 s cells would need"),
    "sirt 1e5": (lambda s: sirt(s, 10**5), r"^size: a 100000² image would need"),
    "sirt zero weights": (lambda s: sirt(s, 16, weights=np.zeros_like(s.values)),
                          r"^weights are all zero"),
    "tv_fista zero weights": (lambda s: tv_fista(s, 16, weights=np.zeros_like(s.values)),
                              r"^weights are all zero"),
    "cgls empty mask": (lambda s: cgls(s, 16, mask=np.zeros((16, 16), bool)),
                        r"^mask is empty"),
    "tv 1e308": (lambda s: tv_fista(s, 16, tv=1e308), r"^tv must be in \[0, 100\]"),
    "fibonacci 1e10": (lambda s: fibonacci_sphere(10**10), r"^n: 10000000000 directions"),
    "tabulated 1e308": (lambda s: Tabulated([0, 90], [1e308, 1e308]),
                        r"^values must be in \[0, 1e\+12\]"),
    "complex sinogram": (lambda s: ml.Sinogram(s.values * (1 + 1j), angles_deg=s.angles_deg,
                                               bin_edges=s.bin_edges),
                         r"^values must be real numbers; got a complex array"),
    "bins 1e308 wide": (lambda s: ml.Ladar.centered(10, 1e308),
                        r"^bin_width must be in \[1e-200, 2e\+29\]; got 1e\+308"),
    "bins 1e-320 wide": (lambda s: ml.Ladar.centered(8, 1e-320),
                         r"^bin_width must be in \[1e-200, 2.5e\+29\]; got 1e-320"),
    "segments 1e7": (lambda s: ml.phantoms.scene("disk").tessellate(10**7),
                     r"^segments: a prism of 10000000 segments would need"),
    "fbp3d smooth 1e6": (lambda s: _fbp3d_smooth(1e6),
                         r"^smooth must be in \[0, 16\]; got 1000000.0"),
    "resolve 1000^3 cells": (lambda s: _resolve_cube(1000),
                             r"^axes: 1 views of 1000 x 1000 x 1000 cells would need"),
}


def _fbp3d_smooth(smooth):
    from meshladar.reconstruct.volumes import fbp3d

    ladar = ml.Ladar(None, np.linspace(-1.0, 1.0, 17), view_vectors=fibonacci_sphere(64))
    sino = ml.Sinogram(np.ones((64, 16)), angles_deg=ladar.angles_deg, bin_edges=ladar.bin_edges,
                       view_vectors=ladar.view_vectors)
    return fbp3d(sino, size=8, smooth=smooth)


def _resolve_cube(n):
    import trimesh

    from meshladar.forward.resolved import resolve

    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=1),
                               material=ml.materials.DARK_GRAY)
    e = np.linspace(-1.0, 1.0, n + 1)
    return resolve(scene, ml.Ladar(angles_deg=[0.0], bin_edges=e),
                   [("range", e), ("cross_range", e), ("elevation", e)])


@pytest.mark.parametrize("case", list(CASES))
def test_refused_with_one_line_naming_the_argument(case, sino):
    call, message = CASES[case]
    with pytest.raises(ParameterError, match=message) as exc:
        call(sino)
    assert "\n" not in str(exc.value)


@pytest.mark.filterwarnings("ignore:.* views are too few")      # few views on purpose: speed
def test_fbp_warns_when_the_data_cannot_make_an_image(sino):
    """Identical angles gave a streak and one bin a flat disk, without a word."""
    same = ml.Sinogram(sino.values, angles_deg=np.zeros(36), bin_edges=sino.bin_edges)
    with pytest.warns(ml.errors.MeshladarWarning, match=r"^all 36 views are at 0 degrees: "
                                                        r"FBP smears one profile"):
        ml.fbp(same, 16)
    one = ml.Sinogram(np.ones((36, 1)), angles_deg=sino.angles_deg, bin_edges=[-1.0, 1.0])
    with pytest.warns(ml.errors.MeshladarWarning, match=r"^one range bin: the image has no "
                                                        r"range resolution"):
        ml.fbp(one, 16)


def test_tv_zero_is_fista_without_regularisation(sino):
    """tv=0 divided by zero in the TV step (NaN image); it is plain FISTA: its data
    residual falls as far as CGLS's on the same data."""
    img = tv_fista(sino, 32, tv=0.0, n_iter=30, extent=1.0)
    assert np.all(np.isfinite(img.values))
    ref = cgls(sino, 32, n_iter=30, extent=1.0)
    assert img.info["residuals"][-1] <= 1.5 * ref.info["residuals"][-1]


@pytest.mark.parametrize("seed", [-1, 1.5, "a", object()], ids=repr)
def test_the_fits_check_their_seed_first(sino, seed):
    """fit_coatings and find_shapes passed a bad seed to numpy deep inside (TypeError)."""
    from meshladar.fit import fit_coatings
    from meshladar.fit.shapes import find_shapes

    with pytest.raises(ParameterError, match="^seed must be None or a non-negative integer"):
        find_shapes(sino, size=16, seed=seed)
    scene = ml.Scene([ml.Disk((0.0, 0.0), 0.6, ml.materials.DARK_GRAY, name="disk")])
    with pytest.raises(ParameterError, match="^seed must be None or a non-negative integer"):
        fit_coatings(scene, sino, seed=seed)


def _scaled(sino, factor, shift=0.0):
    """The sinogram times ``factor``, plus ``shift`` times its peak."""
    values = factor * sino.values + shift * sino.values.max()
    return ml.Sinogram(values, angles_deg=sino.angles_deg, bin_edges=sino.bin_edges)


def _disk_scene():
    return ml.Scene([ml.Disk((0.0, 0.0), 0.6, ml.materials.DARK_GRAY, name="disk")])


FIT_CASES = {
    "fit zero data": (lambda s: fit_coatings(_disk_scene(), _scaled(s, 0.0)),
                      r"^measured has no positive value: nothing returned"),
    "fit negative data": (lambda s: fit_coatings(_disk_scene(), _scaled(s, -1.0)),
                          r"^measured has no positive value"),
    "fit bounds outside": (lambda s: fit_coatings(_disk_scene(), s,
                                                  bounds={"rho_d": (-1.0, 5.0)}),
                           r"^bounds of disk.rho_d must lie in its valid range \[0, 1\]; "
                           r"got \(-1, 5\)"),
    "poisson negative counts": (lambda s: fit_coatings(_disk_scene(), _scaled(s, 1.0, -0.5),
                                                       noise="poisson", photons_per_unit=1e3),
                                r"^noise='poisson' counts events, which are >= 0"),
    "kernel ray spacing": (lambda s: coating_kernel(ml.phantoms.scene("disk").tessellate(64),
                                                    ml.Ladar.paper(angles_deg=[0.0]),
                                                    ray_spacing=0.01),
                           r"^coating_kernel takes the trace options"),
    "kernel samples 1e9": (lambda s: coating_kernel(_disk_scene(),
                                                    ml.Ladar.paper(angles_deg=[0.0]),
                                                    samples=10**9),
                           r"^samples must be at most 1048576 per boundary"),
    "compensate negated": (lambda s: compensate(_scaled(s, -1.0), ml.materials.DARK_GRAY,
                                                size=64),
                           r"^sino has no positive return to compensate; its largest value "
                           r"is 0 "),
}


@pytest.mark.parametrize("case", list(FIT_CASES))
def test_fits_and_compensation_refuse_data_they_cannot_use(case, sino):
    """Each was silent (an all-'undetermined' fit of zeros, σ shrunk by bounds outside the
    valid range, an empty kernel), a minutes-long hang, or a message naming an internal
    quantity ("first has no bright ridge")."""
    call, message = FIT_CASES[case]
    with pytest.raises(ParameterError, match=message):
        call(sino)


def test_an_integer_beyond_float64_is_a_clear_error(tmp_path):
    """A 400-digit integer in a material table was an internal error (OverflowError)."""
    from meshladar.cli import main

    table = tmp_path / "big.toml"
    table.write_text(f"[huge]\nrho_d = {'9' * 400}\nepsilon = 0.1\nb = 0.5\ne = 0.1\n")
    with pytest.raises(ParameterError, match=r"^rho_d must be finite and in \[0, 1\]; got inf"):
        ml.brdf.SandfordRobertson(rho_d=10 ** 400, epsilon=0.1, b=0.5, e=0.1)
    assert main(["materials", str(table)]) == 2


def test_a_users_value_is_quoted_short():
    """Messages printed whole arrays (issue 29, class 7): a quotation is cut to one line."""
    from meshladar._validate import MAX_QUOTE, finite_array

    with pytest.raises(ParameterError) as exc:
        finite_array("values", [10 ** 400] + [1] * 10000)
    quoted = str(exc.value).split("; got ", 1)[1]
    assert len(quoted) == MAX_QUOTE and quoted.endswith("...")


def _far_sphere_warnings(standoff):
    import trimesh

    scene = ml.Scene.from_mesh(trimesh.creation.icosphere(subdivisions=2, radius=0.5),
                               material=ml.materials.lambertian(0.5))
    ladar = ml.Ladar([0.0], np.linspace(-0.5, 0.5, 100_001))           # 1e-5-wide bins
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ml.simulate(scene, ladar, model="mesh", mode="3d", ray_spacing=0.05,
                    sensor=Sensor(standoff=standoff))
    return [str(w.message) for w in caught if "float64 rounding" in str(w.message)]


def test_a_standoff_whose_rounding_reaches_the_bins_warns():
    """Ranges R − D round to ~D·2⁻⁵³: at D = 1e9 m that is 1.1e-7 m, 0.011 of 1e-5-wide
    bins (over STANDOFF_ROUNDING_SHARE = 1e-3: a warning naming it); at 1e3 m, 1e-8 of a
    bin (none). A standoff of 1e15 (issue 29: a 119 % error without a word) is refused."""
    (message,) = _far_sphere_warnings(1e9)
    assert re.search(r"standoff 1e\+09 leaves the ranges a float64 rounding of ~1\.1e-07, "
                     r"0\.011 of the narrowest bin", message), message
    assert _far_sphere_warnings(1e3) == []
    with pytest.raises(ParameterError, match=r"^standoff must be in \(0, 1e\+09\]"):
        Sensor(standoff=1e15)
