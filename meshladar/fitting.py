"""Coatings from ladar data: fit BRDF parameters of chosen parts to a measured sinogram,
the geometry known, with uncertainties and an identifiability report.

The geometry is traced once. :class:`CoatingKernel` keeps it as, per part, a sparse matrix
from the part's monostatic BRDF F(θ; −θ) tabulated on a fine grid of incidence angles
(the projected weight F cos θ, finite to the horizon; linear interpolation, 8193 points on
[0, π/2]: 1.9e-4 rad, fine for a 0.007 rad glint) to the sinogram's bins; any coating is then a matrix-vector product (milliseconds), and a
parameter's derivative is the product with the derivative of its table.

* From analytic shapes (:func:`coating_kernel` on a :class:`~meshladar.Scene`): each
  boundary sampled densely at arc-length weights, front-facing and unshadowed points
  binned by range (exact ray-ellipse occlusion); the weight is F cos θ dl (``"paper"``) or
  F cos² θ dl (``"power"``). Agrees with the analytic model's exact profiles to 0.5 %.
* From mesh hits (:func:`coating_kernel` on :class:`~meshladar.raytrace.hits.Hits`): each
  hit binned at its range with the weights :func:`~meshladar.weigh` gives it, per material
  index; equal to ``weigh`` to the table's interpolation.

:func:`fit_coatings` minimises the misfit over the free parameters within bounds: least
squares (``noise="gaussian"``, σ estimated from the residuals) or the Poisson or speckle
(negative binomial, M cells) likelihood of photoelectron counts, by iteratively reweighted
least squares (the score equations Σ (d − m)/V(m) ∂m/∂p = 0 are the maximum-likelihood ones
for V(m) = m and V(m) = m + m²/M). The covariance is the inverse Fisher information
(Jᵀ V⁻¹ J)⁻¹, optionally checked by a parametric bootstrap; the report names the
parameters the data cannot determine (no effect on the data, or an uncertainty beyond
their range, or a near-perfect correlation with another) and warns.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from ._validate import check_choice, check_count, check_real
from .errors import MeshladarWarning, ParameterError

__all__ = ["CoatingKernel", "coating_kernel", "fit_coatings", "CoatingFit",
           "IdentifiabilityWarning", "design_views", "ViewDesign", "NOISE_MODELS",
           "SR_BOUNDS"]

#: θ samples of the tables on [0, π/2].
GRID = 8193
_THETA = np.linspace(0.0, 0.5 * math.pi, GRID)
#: Noise models of :func:`fit_coatings`.
NOISE_MODELS = ("gaussian", "poisson")
#: Default bounds of the Sandford-Robertson parameters.
SR_BOUNDS = {"rho_d": (0.0, 1.0), "epsilon": (0.0, 1.0), "b": (0.0, 1.0), "e": (1e-4, 1.0)}
#: A parameter is called undetermined when its standard error exceeds this share of its
#: bounds' width (or of its value where unbounded), or when it is correlated beyond
#: _CORR_LIMIT with another and its standard error exceeds _LOOSE of its value.
_REL_LIMIT = 0.5
_CORR_LIMIT = 0.995
_LOOSE = 0.25


class IdentifiabilityWarning(MeshladarWarning):
    """A fitted parameter that the data cannot determine."""


def _table(material):
    """The projected weight F(θ; −θ) cos θ on the θ grid (1/sr; finite up to the horizon,
    where F itself is not)."""
    from .brdf import projected_weight

    return np.asarray(projected_weight(material, np.cos(_THETA), np.sin(_THETA)), dtype=float)


@dataclass(frozen=True, eq=False)
class CoatingKernel:
    """The geometry of a scene under a ladar, ready to be re-weighed for any coatings.

    Attributes
    ----------
    matrices : tuple of scipy.sparse.csr_matrix
        Per part, (n_views · n_bins, GRID): the sinogram is Σ_p matrices[p] @ P_p(θ grid),
        P = F cos θ the part's projected monostatic weight.
    parts : tuple of str
        Part names (shape names or ``"material <i>"``).
    materials : tuple of BRDF
        Each part's coating as traced (the default starting point of a fit).
    shape : (n_views, n_bins)
    angles_deg, bin_edges : arrays
    radiometry : str
    source : str
        "analytic" or "mesh".
    """

    matrices: tuple
    parts: tuple
    materials: tuple
    shape: tuple
    angles_deg: np.ndarray
    bin_edges: np.ndarray
    radiometry: str
    source: str
    info: dict = field(default_factory=dict)

    def _summary(self):
        return (("parts", self.parts), ("shape", self.shape), ("source", self.source),
                ("radiometry", self.radiometry),
                ("nonzeros", int(sum(m.nnz for m in self.matrices))))

    def __repr__(self) -> str:
        from ._summary import text

        return text("CoatingKernel", *self._summary())

    def _repr_html_(self) -> str:
        from ._summary import table

        return table("CoatingKernel", *self._summary())

    def part_index(self, part) -> int:
        """A part's index from its name or index."""
        if isinstance(part, (int, np.integer)) and not isinstance(part, bool):
            if 0 <= part < len(self.parts):
                return int(part)
        elif part in self.parts:
            return self.parts.index(part)
        raise ParameterError(f"part must be one of {list(self.parts)} or an index below "
                             f"{len(self.parts)}; got {part!r}")

    def contribution(self, part, material) -> np.ndarray:
        """One part's sinogram values (n_views, n_bins) with ``material``."""
        return (self.matrices[self.part_index(part)] @ _table(material)).reshape(self.shape)

    def predict(self, materials=None) -> np.ndarray:
        """The sinogram values with ``materials`` (one per part; default as traced)."""
        mats = self.materials if materials is None else tuple(materials)
        if len(mats) != len(self.parts):
            raise ParameterError(f"materials must give {len(self.parts)} coatings, one per "
                                 f"part {list(self.parts)}; got {len(mats)}")
        return sum(self.contribution(i, m) for i, m in enumerate(mats))

    def received(self, sample_rate, *, pulse=None, response=None, standoff=0.0,
                 oversample=8):
        """The kernel of the waveforms a digitiser records (:func:`meshladar.receive` with
        these arguments, which is linear in the bins): each part's matrix composed with the
        per-view map from bins to samples. ``bin_edges`` become the samples' time edges
        (s) and :meth:`predict` gives waveform values; fit them with
        :func:`fit_coatings` and the measured :class:`~meshladar.receiver.Waveforms`."""
        from scipy.sparse import csr_matrix, identity, kron

        from .receiver import receive
        from .sinogram import Sinogram

        if self.source.endswith("waveforms"):
            raise ParameterError("this kernel already gives waveforms")
        n_views, n_bins = self.shape
        unit = Sinogram(np.eye(n_bins), angles_deg=np.zeros(n_bins),
                        bin_edges=self.bin_edges, info={"radiometry": self.radiometry})
        w = receive(unit, sample_rate=sample_rate, pulse=pulse, response=response,
                    standoff=standoff, oversample=oversample)
        R = np.array(w.values).T                                   # (samples, bins)
        R[np.abs(R) < 1e-12 * float(np.abs(R).max(initial=0.0))] = 0.0
        block = kron(identity(n_views, format="csr"), csr_matrix(R), format="csr")
        return CoatingKernel(tuple(block @ m for m in self.matrices), self.parts,
                             self.materials, (n_views, R.shape[0]), self.angles_deg,
                             np.asarray(w.time_edges), self.radiometry,
                             f"{self.source} waveforms",
                             {**self.info, "sample_rate": float(sample_rate),
                              "pulse": repr(pulse), "response": repr(response)})

    def sinogram(self, materials=None):
        """:meth:`predict` as a :class:`~meshladar.Sinogram`."""
        from .sinogram import Sinogram

        return Sinogram(self.predict(materials), angles_deg=self.angles_deg,
                        bin_edges=self.bin_edges, model=f"kernel ({self.source})",
                        info={"radiometry": self.radiometry, **self.info})


def _interp_matrix(rows, theta, omega, n_rows):
    """The sparse (n_rows, GRID) matrix putting weight ω at angle θ into row ``rows`` by
    linear interpolation on the θ grid."""
    from scipy.sparse import csr_matrix

    u = np.clip(theta, 0.0, 0.5 * math.pi) / (_THETA[1] - _THETA[0])
    j = np.minimum(np.floor(u).astype(np.int64), GRID - 2)
    f = u - j
    r = np.concatenate([rows, rows])
    c = np.concatenate([j, j + 1])
    v = np.concatenate([omega * (1.0 - f), omega * f])
    return csr_matrix((v, (r, c)), shape=(n_rows, GRID))


def _ray_blocked(p, w, shape):
    """(N, V) bool: does the ray p + s w, s > 0, cross the ellipse ``shape``?"""
    from .shapes import to_frame

    a, b = shape.axes
    d = p - np.asarray(shape.center)
    qx, qy = to_frame(shape.angle, d[:, 0], d[:, 1])
    dx, dy = to_frame(shape.angle, w[:, 0], w[:, 1])
    qx, qy, dx, dy = qx[:, None] / a, qy[:, None] / b, dx[None, :] / a, dy[None, :] / b
    A = dx * dx + dy * dy
    B = qx * dx + qy * dy
    C = qx * qx + qy * qy - 1.0
    disc = B * B - A * C
    far = (-B + np.sqrt(np.maximum(disc, 0.0))) / A
    return (disc > 0) & (far > 0) & (C > 0)


def _analytic_kernel(scene, ladar, radiometry, samples):
    from .shapes import from_frame

    edges = ladar.bin_edges
    n_views, n_bins = ladar.n_views, edges.size - 1
    phi = np.deg2rad(ladar.angles_deg)
    w = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    mats, names = [], []
    for i, shape in enumerate(scene.shapes):
        a, b = shape.axes
        t = (np.arange(samples) + 0.5) * (2.0 * math.pi / samples)
        p = shape.boundary(t)
        speed = np.hypot(a * np.sin(t), b * np.cos(t))
        dl = speed * (2.0 * math.pi / samples)
        nx, ny = from_frame(shape.angle, b * np.cos(t), a * np.sin(t))
        n = np.stack([nx, ny], axis=1) / np.hypot(nx, ny)[:, None]
        c = n @ w.T                                               # (N, V)
        ok = c > 0
        for j, other in enumerate(scene.shapes):
            if j != i:
                ok &= ~_ray_blocked(p, w, other)
        r = -(p @ w.T)
        k = np.searchsorted(edges, r, side="right") - 1
        ok &= (k >= 0) & (k < n_bins)
        si, vi = np.nonzero(ok)
        cos_t = c[si, vi]
        omega = dl[si] * (1.0 if radiometry == "paper" else cos_t)          # × F cos θ
        mats.append(_interp_matrix(vi * n_bins + k[si, vi], np.arccos(np.minimum(cos_t, 1.0)),
                                   omega, n_views * n_bins))
        names.append(shape.name if shape.name is not None else f"shape {i}")
    if len(set(names)) != len(names):
        names = [f"{nm} ({i})" for i, nm in enumerate(names)]
    return CoatingKernel(tuple(mats), tuple(names), tuple(s.material for s in scene.shapes),
                         (n_views, n_bins), ladar.angles_deg, edges, radiometry, "analytic",
                         {"samples_per_shape": samples, "units": "length/sr"})


def _mesh_kernel(hits, radiometry):
    if hits.bistatic is not None:
        raise ParameterError("coating kernels are monostatic; these hits are bistatic")
    edges = hits.ladar.bin_edges
    n_views, n_bins = hits.ladar.n_views, edges.size - 1
    k = np.searchsorted(edges, hits.range, side="right") - 1
    ok = (hits.cos_theta >= 0) & (k >= 0) & (k < n_bins)
    # weigh's F·δA⊥ (paper) or F cos θ·δA⊥ (power) as ω × the table's F cos θ
    omega = np.full(hits.view.size, float(hits.area))
    if hits.weight_factor is not None:
        omega = omega * hits.weight_factor
    if radiometry == "power":
        if hits.receive_factor is not None:
            omega = omega * hits.receive_factor
    else:
        from .precision import TINY

        omega = omega / np.maximum(hits.cos_theta, TINY)
    theta = np.arctan2(hits.sin_theta, np.maximum(hits.cos_theta, 0.0))
    rows = hits.view.astype(np.int64) * n_bins + k
    mats = []
    for m in range(len(hits.materials)):
        sel = ok & (hits.material == m)
        mats.append(_interp_matrix(rows[sel], theta[sel], omega[sel], n_views * n_bins))
    names = tuple(getattr(m, "name", None) or f"material {i}"
                  for i, m in enumerate(hits.materials))
    if len(set(names)) != len(names):
        names = tuple(f"material {i}" for i in range(len(names)))
    return CoatingKernel(tuple(mats), names, tuple(hits.materials), (n_views, n_bins),
                         hits.ladar.angles_deg, edges, radiometry, "mesh",
                         {"mode": hits.mode, "normals": hits.normals})


def coating_kernel(geometry, ladar=None, *, radiometry="paper", samples=8192):
    """The :class:`CoatingKernel` of analytic shapes (``geometry`` a Scene of disks and
    ellipses, with ``ladar``) or of traced mesh hits (``geometry`` the
    :class:`~meshladar.raytrace.hits.Hits` of :func:`meshladar.trace`; monostatic, point
    binning). ``samples`` per analytic boundary."""
    from .raytrace.hits import Hits
    from .scene import Scene
    from .sensor import check_radiometry

    radiometry = "power" if check_radiometry(radiometry) else "paper"
    if isinstance(geometry, Hits):
        return _mesh_kernel(geometry, radiometry)
    if isinstance(geometry, Scene):
        if ladar is None:
            raise ParameterError("an analytic scene's kernel needs the ladar (views, bins)")
        if not all(hasattr(s, "axes") for s in geometry.shapes):
            raise ParameterError("coating_kernel takes analytic shapes (Disk, Ellipse) or "
                                 "mesh Hits; trace a mesh scene with meshladar.trace first")
        return _analytic_kernel(geometry, ladar, radiometry, check_count("samples", samples))
    raise ParameterError(f"geometry must be a Scene of analytic shapes or Hits; got "
                         f"{type(geometry).__name__}")


# --------------------------------------------------------------------------- fitting


def _float_fields(material):
    if not dataclasses.is_dataclass(material):
        return ()
    return tuple(f.name for f in dataclasses.fields(material)
                 if f.init and f.name != "name" and isinstance(getattr(material, f.name),
                                                                 (float, int))
                 and not isinstance(getattr(material, f.name), bool))


@dataclass(frozen=True)
class _Param:
    part: int
    name: str
    low: float
    high: float

    @property
    def label(self):
        return f"{self.part}.{self.name}"


@dataclass(frozen=True, eq=False)
class CoatingFit:
    """The result of :func:`fit_coatings`.

    Attributes
    ----------
    names : tuple of str
        "part.parameter" of each free parameter.
    estimate, stderr : (n,) arrays
    covariance, correlation : (n, n) arrays
        From the Fisher information at the estimate.
    materials : tuple of BRDF
        Every part's coating with the estimates in.
    identifiable : dict
        name → True, or the reason the data cannot determine it.
    noise, deviance, dof, iterations, predicted
        The noise model, the misfit (χ² for Gaussian, deviance for counts), degrees of
        freedom, solver iterations, the fitted sinogram values.
    bootstrap : (n_boot, n) array or None
        Parametric-bootstrap estimates.
    """

    names: tuple
    estimate: np.ndarray
    stderr: np.ndarray
    covariance: np.ndarray
    correlation: np.ndarray
    materials: tuple
    identifiable: dict
    noise: str
    deviance: float
    dof: int
    iterations: int
    predicted: np.ndarray
    bootstrap: np.ndarray | None = None
    info: dict = field(default_factory=dict)

    def _summary(self):
        return (("noise", self.noise),
                *((n, f"{v:.5g} ± {e:.3g}" + ("" if self.identifiable[n] is True
                                               else " (undetermined)"))
                  for n, v, e in zip(self.names, self.estimate, self.stderr)),
                ("misfit", f"{self.deviance:.4g} on {self.dof} dof"))

    def __repr__(self) -> str:
        from ._summary import text

        return text("CoatingFit", *self._summary())

    def _repr_html_(self) -> str:
        from ._summary import table

        return table("CoatingFit", *self._summary())

    def interval(self, level=0.95):
        """(low, high) arrays: estimate ∓ z σ (normal approximation)."""
        from scipy.stats import norm

        level = check_real("level", level, low=0.0, high=1.0, low_open=True, high_open=True)
        z = float(norm.ppf(0.5 + 0.5 * level))
        return self.estimate - z * self.stderr, self.estimate + z * self.stderr

    def report(self):
        """The fit as text lines: each parameter ± σ, its 95 % interval, and whether the
        data determine it."""
        lo, hi = self.interval()
        out = [f"  coating fit ({self.noise}; misfit {self.deviance:.4g} on {self.dof} "
               f"degrees of freedom, {self.iterations} iterations)",
               f"  {'parameter':<26} {'estimate':>11} {'± σ':>10} {'95 % interval':>24}"]
        for i, n in enumerate(self.names):
            ok = self.identifiable[n]
            note = "" if ok is True else f"  NOT DETERMINED: {ok}"
            out.append(f"  {n:<26} {self.estimate[i]:11.5g} {self.stderr[i]:10.3g} "
                       f"[{lo[i]:10.5g}, {hi[i]:10.5g}]{note}")
        strong = [(self.names[i], self.names[j], self.correlation[i, j])
                  for i in range(len(self.names)) for j in range(i + 1, len(self.names))
                  if abs(self.correlation[i, j]) > 0.9]
        for a, b, r in strong:
            out.append(f"  correlation {a} ~ {b}: {r:+.3f}")
        return out


def _resolve_params(kernel, parts, free, bounds, initial):
    from .brdf import SandfordRobertson

    mats = list(kernel.materials)
    if initial is not None:
        for key, m in dict(initial).items():
            mats[kernel.part_index(key)] = m
    chosen = range(len(kernel.parts)) if parts is None else [kernel.part_index(p)
                                                            for p in parts]
    chosen = sorted(set(chosen))
    params = []
    for p in chosen:
        m = mats[p]
        names = _float_fields(m)
        if free is not None:
            want = free.get(kernel.parts[p], free.get(p)) if isinstance(free, dict) else free
            if want is None:
                continue
            want = (want,) if isinstance(want, str) else tuple(want)
            bad = [n for n in want if n not in names]
            if bad:
                raise ParameterError(f"free parameters of part {kernel.parts[p]!r} must be "
                                     f"among {list(names)}; got {bad}")
            names = want
        elif isinstance(m, SandfordRobertson):
            names = tuple(n for n in ("rho_d", "epsilon", "b", "e")
                          if not (m.lobes == "diffuse" and n in ("epsilon", "e")))
        if not names:
            raise ParameterError(f"part {kernel.parts[p]!r}: {type(m).__name__} has no float "
                                 "dataclass fields to fit; give free=")
        for n in names:
            lo, hi = SR_BOUNDS.get(n, (-math.inf, math.inf)) if isinstance(
                m, SandfordRobertson) else (-math.inf, math.inf)
            if bounds is not None:
                for key in (f"{kernel.parts[p]}.{n}", f"{p}.{n}", n):
                    if key in bounds:
                        lo, hi = (float(v) for v in bounds[key])
                        break
            if not lo < hi:
                raise ParameterError(f"bounds of {kernel.parts[p]}.{n} must be (low, high) "
                                     f"with low < high; got ({lo}, {hi})")
            params.append(_Param(p, n, lo, hi))
    if not params:
        raise ParameterError("nothing to fit: no free parameters in the chosen parts")
    return mats, params


def _materials(mats, params, x):
    out = list(mats)
    by_part = {}
    for prm, v in zip(params, x):
        by_part.setdefault(prm.part, {})[prm.name] = float(v)
    for p, kw in by_part.items():
        out[p] = dataclasses.replace(out[p], **kw)
    return out


def _jacobian(K, mats, params, x, base, scale, n_rows):
    """∂(model)/∂(parameters), (n_rows, n): each parameter's table derivative by a one-sided
    step into its bounds, through its part's matrix ``K[part]``."""
    J = np.zeros((n_rows, len(params)))
    if base is None:
        return J
    for p in sorted({q.part for q in params}):
        cols = [i for i, prm in enumerate(params) if prm.part == p]
        D = np.zeros((GRID, len(cols)))
        for c, i in enumerate(cols):
            prm = params[i]
            h = 1e-7 * max(1.0, abs(x[i])) if prm.name != "e" else 1e-5 * max(x[i], 1e-4)
            step = h if x[i] + h <= prm.high else -h
            moved = np.array(x, dtype=float)
            moved[i] = x[i] + step
            try:
                D[:, c] = (_table(_materials(mats, params, moved)[p]) - base[p]) / step
            except ParameterError:
                continue
        J[:, cols] = (K[p] @ D) * scale
    return J


def fit_coatings(geometry, measured, *, parts=None, free=None, bounds=None, initial=None,
                 noise="gaussian", photons_per_unit=None, speckle_cells=None, background=0.0,
                 bootstrap=0, seed=0, samples=8192, max_iter=50):
    """Fit coating parameters of chosen parts to a measured sinogram, the geometry known.

    Parameters
    ----------
    geometry : CoatingKernel, Scene or Hits
        The traced geometry (:func:`coating_kernel`); a Scene of analytic shapes is traced
        on the measured sinogram's views and bins.
    measured : Sinogram or Waveforms
        The data (its ``info["radiometry"]`` picks the radiometry for a Scene); waveforms
        need a waveform kernel (:meth:`CoatingKernel.received`).
    parts : sequence, optional
        Parts (names or indices) whose coatings are fitted (default all); the others keep
        their coatings.
    free : sequence or dict, optional
        Parameter names to fit (dataclass fields of each part's BRDF; default all four SR
        parameters, or ρd and b of a diffuse-only SR coating, or every float field of
        another BRDF); a dict gives them per part.
    bounds : dict, optional
        "part.param", "index.param" or "param" → (low, high) (default SR's valid ranges;
        unbounded for other models).
    initial : dict, optional
        part → BRDF to start from (default the geometry's own coatings).
    noise : {"gaussian", "poisson"}
        Least squares with σ from the residuals, or photoelectron counts: Poisson, or with
        ``speckle_cells`` M the negative binomial of M speckle cells per bin.
    photons_per_unit : float
        Counts per unit of ``measured.values`` (required for ``"poisson"``).
    background : float
        Known mean background counts per bin (``"poisson"``), not subtracted from the data.
    bootstrap : int
        Parametric-bootstrap refits (0: none): noise drawn from the fitted model.
    seed : int
        The bootstrap's seed.
    max_iter : int
        Most outer (reweighting) iterations.

    Returns
    -------
    CoatingFit
        Warns :class:`IdentifiabilityWarning` naming any parameter the data cannot
        determine.
    """
    from scipy.optimize import least_squares

    from ._validate import check_sinogram
    from .scene import Scene

    from .receiver import Waveforms

    waveforms = isinstance(measured, Waveforms)
    if not waveforms:
        check_sinogram("measured", measured)
    noise = check_choice("noise", noise, NOISE_MODELS)
    if waveforms and not (isinstance(geometry, CoatingKernel)
                          and geometry.source.endswith("waveforms")):
        raise ParameterError("measured waveforms need the geometry as a waveform kernel: "
                             "coating_kernel(...).received(sample_rate, pulse=...)")
    if isinstance(geometry, CoatingKernel):
        kernel = geometry
    elif isinstance(geometry, Scene):
        from .ladar import Ladar

        kernel = coating_kernel(geometry, Ladar(measured.angles_deg, measured.bin_edges),
                                radiometry=measured.info.get("radiometry", "paper"),
                                samples=samples)
    else:
        kernel = coating_kernel(geometry, radiometry=measured.info.get("radiometry", "paper"))
    if measured.values.shape != kernel.shape:
        raise ParameterError(f"measured has shape {measured.values.shape}; the geometry's "
                             f"views and bins give {kernel.shape}")
    if noise == "poisson":
        if photons_per_unit is None:
            raise ParameterError("noise='poisson' needs photons_per_unit (counts per unit "
                                 "of the measured values)")
        scale = check_real("photons_per_unit", photons_per_unit, low=0.0, low_open=True)
        M = None if speckle_cells is None else check_real("speckle_cells", speckle_cells,
                                                          low=1.0)
        background = check_real("background", background, low=0.0)
    else:
        if speckle_cells is not None or background:
            raise ParameterError("speckle_cells and background belong to noise='poisson'")
        scale, M = 1.0, None
    bootstrap = check_count("bootstrap", bootstrap, low=0)
    max_iter = check_count("max_iter", max_iter)
    mats, params = _resolve_params(kernel, parts, free, bounds, initial)
    data = measured.values.ravel() * scale
    fixed_parts = sorted({i for i in range(len(mats))} - {p.part for p in params})
    fixed = np.zeros(data.size)
    for p in fixed_parts:
        fixed += kernel.matrices[p] @ _table(mats[p])
    fixed = fixed * scale + (background if noise == "poisson" else 0.0)
    low = np.array([p.low for p in params])
    high = np.array([p.high for p in params])
    x0 = np.clip([float(getattr(mats[p.part], p.name)) for p in params], low, high)
    fitted_parts = sorted({q.part for q in params})
    # only the bins a fitted part reaches depend on the parameters
    rows = np.flatnonzero(sum(np.diff(kernel.matrices[p].indptr) for p in fitted_parts))
    K = {p: kernel.matrices[p][rows] for p in fitted_parts}
    y_all, fixed_all = data, fixed
    data, fixed = data[rows], fixed[rows]

    cache = {}

    def tables(x):
        """Each fitted part's table at x (None outside the model's valid set); the last
        few are kept, as the solver asks for the model and its Jacobian at one point."""
        key = tuple(np.asarray(x, float))
        if key not in cache:
            try:
                ms = _materials(mats, params, x)
                cache[key] = {p: _table(ms[p]) for p in fitted_parts}
            except ParameterError:
                cache[key] = None
            if len(cache) > 8:
                cache.pop(next(iter(cache)))
        return cache[key]

    def model(x):
        t = tables(x)
        if t is None:
            return None
        m = fixed.copy()
        for p in fitted_parts:
            m += (K[p] @ t[p]) * scale
        return m

    def jacobian(x):
        return _jacobian(K, mats, params, x, tables(x), scale, data.size)

    def variance(m):
        if noise == "gaussian":
            return np.ones_like(m)
        v = np.maximum(m, 0.0) + (0.0 if M is None else np.maximum(m, 0.0) ** 2 / M)
        return np.maximum(v, 1e-3 * max(1.0, float(np.median(v[v > 0])) if (v > 0).any()
                                          else 1.0))

    def solve(y, x_start):
        x = x_start.copy()
        iterations = 0
        m = model(x)
        if m is None:
            raise ParameterError("the starting coatings are invalid (initial=)")
        for _ in range(max_iter):
            V = variance(m)
            sw = 1.0 / np.sqrt(V)

            def resid(z):
                mz = model(z)
                if mz is None:                           # outside the model's valid set
                    return np.full(y.size, 1e6 * (np.abs(y).max() + 1.0)) * sw
                return (mz - y) * sw

            sol = least_squares(resid, x, jac=lambda z: jacobian(z) * sw[:, None],
                                bounds=(low, high), x_scale="jac", method="trf",
                                max_nfev=200)
            iterations += sol.nfev
            dx = np.abs(sol.x - x)
            x = sol.x
            m = model(x)
            if noise == "gaussian":
                break
            # converged when the reweighting moves no parameter by 1 % of its σ
            Jw = sol.jac
            try:
                sd = np.sqrt(np.abs(np.diag(np.linalg.pinv(Jw.T @ Jw))))
            except np.linalg.LinAlgError:
                sd = np.full(len(params), np.inf)
            if np.all(dx <= 0.01 * sd + 1e-12 * np.abs(x)):
                break
        return x, m, iterations

    x, m, iterations = solve(data, x0)
    V = variance(m)
    J = jacobian(x)
    if noise == "gaussian":
        # σ² from every bin: those no fitted part reaches hold noise (about the fixed
        # parts) too
        outside = float(np.sum((y_all - fixed_all) ** 2)) - float(np.sum((data - fixed) ** 2))
        rss = float(np.sum((data - m) ** 2)) + max(outside, 0.0)
        dof = max(1, y_all.size - len(params))
        # exact data: σ at rounding of the data's scale, not 0
        sigma2 = max(rss / dof, (1e-12 * float(np.abs(y_all).max(initial=1.0))) ** 2)
        misfit = rss / sigma2
        fisher = (J.T @ J) / sigma2
    else:
        dof = max(1, data.size - len(params))
        misfit = float(np.sum((data - m) ** 2 / V))
        fisher = J.T @ (J / V[:, None])
    full = fixed_all.copy()
    full[rows] = m
    m_full = full
    cov, ident = _uncertainty(fisher, x, params, kernel)
    stderr = np.sqrt(np.maximum(np.diag(cov), 0.0))
    d = np.where((stderr > 0) & np.isfinite(stderr), stderr, 1.0)
    corr = np.where(np.isfinite(cov), cov, np.nan) / np.outer(d, d)
    names = tuple(f"{kernel.parts[p.part]}.{p.name}" for p in params)
    ident = {names[i]: v for i, v in enumerate(ident)}
    boots = None
    if bootstrap:
        rng = np.random.default_rng(seed)
        boots = np.empty((bootstrap, len(params)))
        for b in range(bootstrap):
            if noise == "gaussian":
                y = m + rng.normal(0.0, math.sqrt(sigma2), m.size)
            elif M is None:
                y = rng.poisson(np.maximum(m, 0.0)).astype(float)
            else:
                y = rng.poisson(rng.gamma(M, np.maximum(m, 0.0) / M)).astype(float)
            boots[b] = solve(y, x)[0]
    bad = {n: why for n, why in ident.items() if why is not True}
    if bad:
        warnings.warn("the data cannot determine " + "; ".join(
            f"{n} ({why})" for n, why in bad.items()), IdentifiabilityWarning, stacklevel=2)
    return CoatingFit(names, x, stderr, cov, corr, tuple(_materials(mats, params, x)), ident,
                      noise if M is None else f"negative binomial (M = {M:g})", misfit, dof,
                      iterations, (m_full / scale).reshape(kernel.shape), boots,
                      {"photons_per_unit": scale if noise == "poisson" else None,
                       "radiometry": kernel.radiometry, "source": kernel.source})


def _uncertainty(fisher, x, params, kernel):
    """(covariance, per-parameter True or the reason it is undetermined)."""
    n = len(params)
    width = np.array([p.high - p.low if math.isfinite(p.high - p.low) else
                      max(abs(v), 1e-12) for p, v in zip(params, x)])
    scaled = fisher * np.outer(width, width)
    reasons = [True] * n
    diag = np.diag(scaled)
    top = float(diag.max(initial=0.0))
    for i in range(n):
        if diag[i] <= 1e-14 * max(top, 1e-300):
            reasons[i] = "the data do not depend on it"
    live = [i for i in range(n) if reasons[i] is True]
    cov = np.full((n, n), 0.0)
    for i in range(n):
        if reasons[i] is not True:
            cov[i, i] = math.inf
    if live:
        sub = scaled[np.ix_(live, live)]
        try:
            inv = np.linalg.inv(sub)
            if not np.all(np.isfinite(inv)):
                raise np.linalg.LinAlgError
        except np.linalg.LinAlgError:
            inv = np.linalg.pinv(sub)
        cov[np.ix_(live, live)] = inv / np.outer(width[live], width[live])
        sd = np.sqrt(np.maximum(np.diag(inv), 0.0))
        for a, i in enumerate(live):
            if sd[a] > _REL_LIMIT:
                reasons[i] = (f"its uncertainty ({sd[a] * width[i]:.3g}) exceeds half its "
                              f"range")
        corr = inv / np.outer(np.where(sd > 0, sd, 1), np.where(sd > 0, sd, 1))
        loose = {i: sd[a] * width[i] > _LOOSE * max(abs(x[i]), 1e-12)
                 for a, i in enumerate(live)}
        for a, i in enumerate(live):
            for b_, j in enumerate(live):
                if i < j and abs(corr[a, b_]) > _CORR_LIMIT:
                    for k, other in ((i, j), (j, i)):
                        if reasons[k] is True and loose[k]:
                            reasons[k] = (f"it trades off with "
                                          f"{kernel.parts[params[other].part]}."
                                          f"{params[other].name} (correlation "
                                          f"{corr[a, b_]:+.4f})")
    return cov, reasons


# --------------------------------------------------------------------------- design


@dataclass(frozen=True, eq=False)
class ViewDesign:
    """The result of :func:`design_views`.

    Attributes
    ----------
    chosen : (budget,) int array
        Indices of the chosen views, in the order the greedy search added them.
    angles_deg : (n_views,) array
        Every candidate view's angle.
    information : (n_views,) array
        Each candidate alone: log det of its scaled Fisher information (with a small
        ridge), the view's own worth.
    names : tuple of str
    stderr_designed, stderr_uniform : (n,) arrays
        Parameter σ from the chosen views and from ``budget`` evenly spaced views.
    """

    chosen: np.ndarray
    angles_deg: np.ndarray
    information: np.ndarray
    names: tuple
    stderr_designed: np.ndarray
    stderr_uniform: np.ndarray
    uniform: np.ndarray

    def plot(self):
        """A quick look (:func:`meshladar.viz.fitting.design_figure`): a matplotlib
        Figure."""
        from .viz.fitting import design_figure

        return design_figure(self)


def design_views(geometry, budget, *, ladar=None, parts=None, free=None, materials=None,
                 photons_per_unit=None, samples=4096):
    """Which ``budget`` of the candidate views constrain the coatings best: greedy
    D-optimal design on the Fisher information of Poisson counts (each step adds the view
    that most raises log det F of the chosen set), compared with evenly spaced views.

    Parameters
    ----------
    geometry : CoatingKernel, Scene or Hits
        The candidates are its views (a Scene needs ``ladar``).
    budget : int
        Views to choose.
    parts, free
        As :func:`fit_coatings`.
    materials : dict, optional
        part → BRDF, the coatings the design is for (default the geometry's).
    photons_per_unit : float, optional
        Counts per unit of the sinogram (default: 1e5 counts in the brightest bin).
    """
    if isinstance(geometry, CoatingKernel):
        kernel = geometry
    else:
        kernel = coating_kernel(geometry, ladar, samples=samples)
    n_views = kernel.shape[0]
    budget = check_count("budget", budget)
    if budget > n_views:
        raise ParameterError(f"budget must be at most the {n_views} candidate views; got "
                             f"{budget}")
    mats, params = _resolve_params(kernel, parts, free, None, materials)
    x = np.array([float(getattr(mats[p.part], p.name)) for p in params])
    m = kernel.predict(mats).ravel()
    scale = (1e5 / float(m.max()) if photons_per_unit is None else
             check_real("photons_per_unit", photons_per_unit, low=0.0, low_open=True))
    parts_ = sorted({q.part for q in params})
    base = {p: _table(mats[p]) for p in parts_}
    J = _jacobian({p: kernel.matrices[p] for p in parts_}, mats, params, x, base, scale,
                  m.size)
    V = np.maximum(m * scale, 1e-9 * float(m.max()) * scale)
    width = np.array([prm.high - prm.low if math.isfinite(prm.high - prm.low)
                      else max(abs(v), 1e-12) for prm, v in zip(params, x)])
    Js = J * width[None, :]                          # in units of each parameter's range
    n_bins = kernel.shape[1]
    per_view = np.einsum("vbi,vbj->vij", (Js / V[:, None]).reshape(n_views, n_bins, -1),
                         Js.reshape(n_views, n_bins, -1))
    total = per_view.sum(axis=0)
    ridge = 1e-9 * float(np.trace(total)) / len(params) * np.eye(len(params))
    information = np.array([np.linalg.slogdet(F + ridge)[1] for F in per_view])
    chosen, F = [], ridge.copy()
    for _ in range(budget):
        best, gain = -1, -math.inf
        for v in range(n_views):
            if v in chosen:
                continue
            g = np.linalg.slogdet(F + per_view[v])[1]
            if g > gain:
                best, gain = v, g
        chosen.append(best)
        F = F + per_view[best]
    uniform = np.round(np.arange(budget) * n_views / budget).astype(int)

    def stderr(idx):
        Fi = per_view[idx].sum(axis=0) + ridge
        return np.sqrt(np.abs(np.diag(np.linalg.pinv(Fi)))) * width

    names = tuple(f"{kernel.parts[p.part]}.{p.name}" for p in params)
    return ViewDesign(np.array(chosen), np.asarray(kernel.angles_deg), information, names,
                      stderr(chosen), stderr(uniform), uniform)
