"""Coating kernels: the geometry of a scene under a ladar, traced once and re-weighed for
any coatings.

:class:`CoatingKernel` keeps it as, per part, a sparse matrix from the part's monostatic
BRDF F(θ; −θ) tabulated on a fine grid of incidence angles (the projected weight F cos θ,
finite to the horizon; 16385 points on [0, π/2] at θ = (π/2) u², u even: finest where the
glint is, 1.1e-5 rad at θ = 0.007 and 2.4e-6 rad at 2.4e-4, 1.9e-4 rad at the horizon)
to the sinogram's bins; any coating is then a matrix-vector product (milliseconds), and a
parameter's derivative is the product with the derivative of its table.

* From analytic shapes (:func:`coating_kernel` on a :class:`~meshladar.Scene`): each
  boundary cut per view into ``samples`` pieces from the point nearest the ladar, every
  piece's visible part split between bins exactly (``meshladar.fit._sampling``), the table
  interpolated cubically; the weight is F cos θ dl (``"paper"``) or F cos² θ dl
  (``"power"``). The error is second order in the piece length (~4× less per doubling);
  at 8192 pieces the paper's pair is within 1e-4 (relative L2) of the analytic model's
  exact profiles. :meth:`CoatingKernel.resampled` gives the same scene at another count
  (a fit uses it to control the error, ``meshladar.fit._resolution``).
* From mesh hits (:func:`coating_kernel` on :class:`~meshladar.hits.Hits`, or on a mesh
  :class:`~meshladar.Scene` with the ladar, which it traces): each hit binned at its range
  with the weights :func:`~meshladar.weigh` gives it, per material index; equal to
  ``weigh`` to the table's interpolation. A kernel traced here from a Scene keeps the
  scene, so :meth:`CoatingKernel.resampled` traces it again at another count of rays per
  bin width (its error falls ~2× per doubling: point binning at the bins' edges is first
  order); a kernel of the user's own Hits cannot be resampled.

Both are built in ``meshladar.fit._building``; the tables and their θ grid
(:data:`GRID`) are ``meshladar.fit._tables``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.sparse import csr_matrix, identity, kron

from .._summary import table as _html_table
from .._summary import text as _text
from .._validate import check_count, check_real
from ..errors import ParameterError
from ..raytrace.grid import RAYS_PER_BIN_RANGE
from ..hits import Hits
from ..waveforms import receive
from ..scene import Scene
from ..sensor import check_radiometry
from ..sinogram import Sinogram
from ._building import analytic_fields, hits_fields, traced_mesh_fields
from ._params import part_index
from ._tables import GRID, _table

__all__ = ["CoatingKernel", "coating_kernel", "GRID"]


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
        The shape of the sinogram it predicts ((n_views, n_samples) for a waveform
        kernel).
    angles_deg, bin_edges : arrays
        The views (degrees) and the range bin edges (a waveform kernel: the samples' time
        edges, s).
    radiometry : str
        ``"paper"`` or ``"power"``.
    source : str
        "analytic" or "mesh"; "analytic waveforms" or "mesh waveforms" for the kernel of
        :meth:`received`.
    info : dict
        Provenance: ``samples_per_shape`` and ``units`` (analytic); ``mode``, ``normals``,
        ``rays``, and ``ray_spacing`` and ``rays_per_bin`` when traced from a Scene
        (mesh); ``sample_rate``, ``pulse``, ``response`` added by :meth:`received`.
    view_vectors : (n_views, 3) array or None
        The views' unit vectors (the ladar's; None when not known). :func:`fit_coatings`
        refuses data whose views, bin edges or radiometry are not the kernel's.
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
    view_vectors: np.ndarray | None = None
    _traced: tuple | None = field(default=None, repr=False)
    _finer: dict = field(default_factory=dict, repr=False)

    def _summary(self):
        return (("parts", self.parts), ("shape", self.shape), ("source", self.source),
                ("radiometry", self.radiometry),
                ("nonzeros", int(sum(m.nnz for m in self.matrices))))

    def __repr__(self) -> str:
        return _text("CoatingKernel", *self._summary())

    def _repr_html_(self) -> str:
        return _html_table("CoatingKernel", *self._summary())

    @property
    def samples(self):
        """Pieces per analytic boundary, or rays per range-bin width of a mesh kernel traced
        from its Scene (None for a kernel of the user's own Hits)."""
        return self.info.get("samples_per_shape", self.info.get("rays_per_bin"))

    def resampled(self, samples):
        """This kernel with ``samples`` pieces per analytic boundary, or traced again with
        ``samples`` rays per bin width (a mesh kernel traced from its Scene); kept, so a
        second call is free. A kernel of the user's own Hits cannot be resampled
        (ParameterError).

        Parameters
        ----------
        samples : int or float
            Analytic kernel: pieces per boundary, an integer in [1, 2 ×
            :data:`MAX_KERNEL_SAMPLES`] (twice :func:`coating_kernel`'s cap: a fit checks
            a kernel of N pieces against the one of 2N). Mesh kernel: rays per range-bin
            width, a real in the range ``RAYS_PER_BIN_RANGE`` of
            :mod:`meshladar.raytrace.grid` (as :func:`coating_kernel`).

        Returns
        -------
        CoatingKernel
            This kernel when ``samples`` equals its own :attr:`samples`; else the kernel at
            ``samples``, built once and kept on this one.

        Raises
        ------
        ParameterError
            If the kernel was not traced from a Scene here (the user's own Hits, or a
            waveform kernel), or ``samples`` is invalid.
        """
        if self._traced is None:
            raise ParameterError("only a kernel traced from its Scene (coating_kernel(scene, "
                                 f"ladar)) can be resampled; this one is from {self.source}"
                                 + (" hits" if self.source == "mesh" else ""))
        # checked before anything is built: the pieces' arrays grow linearly with samples
        samples = (check_count("samples", samples, high=2 * MAX_KERNEL_SAMPLES)
                   if self.source == "analytic"
                   else check_real("samples", samples, low=RAYS_PER_BIN_RANGE[0],
                                   high=RAYS_PER_BIN_RANGE[1]))
        if samples == self.samples:
            return self
        if samples not in self._finer:
            scene, ladar, *options = self._traced
            self._finer[samples] = CoatingKernel(**(
                analytic_fields(scene, ladar, self.radiometry, samples)
                if self.source == "analytic"
                else traced_mesh_fields(scene, ladar, self.radiometry, samples, *options)))
        return self._finer[samples]

    @property
    def rays(self):
        """Rays a mesh kernel traced, over all views (None for an analytic kernel)."""
        return self.info.get("rays")

    def part_index(self, part) -> int:
        """A part's index from its name or index.

        Parameters
        ----------
        part : str or int
            A name in :attr:`parts`, or an index in [0, n_parts) (bools are refused).

        Returns
        -------
        int
            The part's index into :attr:`parts` and :attr:`matrices`.

        Raises
        ------
        ParameterError
            If ``part`` is neither.
        """
        return part_index(self.parts, part)

    def contribution(self, part, material) -> np.ndarray:
        """One part's sinogram values (n_views, n_bins) with ``material``.

        Parameters
        ----------
        part : str or int
            The part's name or index (:meth:`part_index`).
        material : BRDF
            The coating, evaluated through its projected monostatic weight on the
            :data:`GRID` angles.

        Returns
        -------
        (n_views, n_bins) float64
            The part's share of the sinogram (:attr:`shape`).

        Raises
        ------
        ParameterError
            If ``part`` names no part.
        """
        return (self.matrices[self.part_index(part)] @ _table(material)).reshape(self.shape)

    def predict(self, materials=None) -> np.ndarray:
        """The sinogram values with ``materials`` (one per part; default as traced).

        Parameters
        ----------
        materials : sequence of BRDF, optional
            One coating per part, in the order of :attr:`parts` (default
            :attr:`materials`).

        Returns
        -------
        (n_views, n_bins) float64
            The sum of every part's :meth:`contribution` (:attr:`shape`).

        Raises
        ------
        ParameterError
            If ``materials`` does not give one coating per part.
        """
        mats = self.materials if materials is None else tuple(materials)
        if len(mats) != len(self.parts):
            raise ParameterError(f"materials must give {len(self.parts)} coatings, one per "
                                 f"part {list(self.parts)}; got {len(mats)}")
        return sum(self.contribution(i, m) for i, m in enumerate(mats))

    def received(self, sample_rate, *, pulse=None, response=None, standoff=0.0,
                 oversample=8):
        """The kernel of the waveforms a digitiser records
        (:func:`meshladar.waveforms.receive` with these arguments, which is linear in the
        bins): each part's matrix composed with the per-view map from bins to samples.
        ``bin_edges`` become the samples' time edges (s) and :meth:`predict` gives
        waveform values; fit them with :func:`fit_coatings` and the measured
        :class:`~meshladar.waveforms.Waveforms`.

        The map's entries below 1e-12 of its largest are set to 0 (kept sparse).

        Parameters
        ----------
        sample_rate : float
            Digitiser rate, Hz, as :func:`meshladar.waveforms.receive` checks it.
        pulse : GaussianPulse or SampledPulse, optional
            The transmitted pulse (default none, a Dirac pulse).
        response : GaussianPulse or SampledPulse, optional
            The receiver's impulse response (default none, ideal).
        standoff : float, optional
            D (m) for the time origin t = 2(r + D)/c (default 0.0).
        oversample : int, optional
            Fine cells per digitiser sample for the convolutions (default 8).

        Returns
        -------
        CoatingKernel
            Of shape (n_views, n_samples), ``bin_edges`` the samples' time edges (s),
            source ``"<source> waveforms"``; it cannot be resampled.

        Raises
        ------
        ParameterError
            If this kernel already gives waveforms, or
            :func:`meshladar.waveforms.receive` refuses an argument.
        """
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
                              "pulse": repr(pulse), "response": repr(response)},
                             self.view_vectors)

    def sinogram(self, materials=None):
        """:meth:`predict` as a :class:`~meshladar.Sinogram`.

        Parameters
        ----------
        materials : sequence of BRDF, optional
            One coating per part (default as traced).

        Returns
        -------
        Sinogram
            ``values`` (n_views, n_bins), the kernel's ``angles_deg`` and ``bin_edges``,
            model ``"kernel (<source>)"``, ``info`` the radiometry and the kernel's
            :attr:`info`.

        Raises
        ------
        ParameterError
            If ``materials`` does not give one coating per part.
        """
        return Sinogram(self.predict(materials), angles_deg=self.angles_deg,
                        bin_edges=self.bin_edges, model=f"kernel ({self.source})",
                        info={"radiometry": self.radiometry, **self.info})


#: Options of :func:`meshladar.trace` a mesh scene's kernel takes (the ray spacing is the
#: kernel's own ``samples``, rays per bin width; a bistatic receiver has no kernel).
TRACE_OPTIONS = ("mode", "normals", "back_faces", "z0", "sampling", "seed", "backend",
                 "sensor")


#: The most samples per analytic boundary a kernel takes (16 times the fit's refinement cap;
#: 1e9 ran for minutes before running out of memory).
MAX_KERNEL_SAMPLES = 2 ** 20


def coating_kernel(geometry, ladar=None, *, radiometry="paper", samples=None, **trace):
    """The :class:`CoatingKernel` of a scene under a ladar, for re-weighing with any
    coatings.

    Parameters
    ----------
    geometry : Scene or Hits
        A Scene of analytic shapes (Disk, Ellipse; views about the z axis), a mesh Scene
        (traced here with :func:`meshladar.trace`), or the :class:`~meshladar.hits.Hits`
        of a trace (monostatic, point binning).
    ladar : Ladar
        Views and bins; required with a Scene (Hits carry their own).
    radiometry : {"paper", "power"}
    samples : float, optional
        Pieces per analytic boundary (default 8192, at most :data:`MAX_KERNEL_SAMPLES`),
        or rays per range-bin width of a mesh scene (default :func:`~meshladar.trace`'s).
    **trace
        Options of :func:`~meshladar.trace` for a mesh scene (:data:`TRACE_OPTIONS`:
        mode, normals, back_faces, z0, sampling, seed, backend, sensor).

    Returns
    -------
    CoatingKernel
        Traced from a Scene, it can be :meth:`~CoatingKernel.resampled`, which is how
        :func:`fit_coatings` controls its error.

    Raises
    ------
    ParameterError
        If ``radiometry`` is invalid; a keyword is not among :data:`TRACE_OPTIONS`; Hits
        come with a ``ladar``, ``samples`` or trace options; ``geometry`` is neither a
        Scene nor Hits, or its Hits are bistatic; a Scene comes without a ``ladar``; an
        analytic Scene gets trace options, holds shapes other than disks and ellipses, or
        meets views off the x-y plane; or ``samples`` is not an integer in
        [1, :data:`MAX_KERNEL_SAMPLES`] (analytic) or a real in the range
        ``RAYS_PER_BIN_RANGE`` of :mod:`meshladar.raytrace.grid` (mesh).
    """
    radiometry = "power" if check_radiometry(radiometry) else "paper"
    unknown = sorted(set(trace) - set(TRACE_OPTIONS))
    if unknown:
        raise ParameterError(f"coating_kernel takes the trace options {list(TRACE_OPTIONS)}; "
                             f"got {unknown}" + (" (the ray spacing is samples=, rays per "
                                                 "bin width)" if {"ray_spacing",
                                                 "rays_per_bin"} & set(unknown) else ""))
    if isinstance(geometry, Hits):
        if ladar is not None or samples is not None or trace:
            raise ParameterError("Hits carry their ladar and rays: give coating_kernel(hits) "
                                 "alone, or the mesh Scene with the ladar and samples")
        return CoatingKernel(**hits_fields(geometry, radiometry))
    if not isinstance(geometry, Scene):
        raise ParameterError(f"geometry must be a Scene of analytic shapes or Hits; got "
                             f"{type(geometry).__name__}")
    if ladar is None:
        raise ParameterError("a scene's kernel needs the ladar (views, bins)")
    if geometry.is_mesh:
        if samples is not None:
            samples = check_real("samples", samples, low=RAYS_PER_BIN_RANGE[0],
                                 high=RAYS_PER_BIN_RANGE[1])
        return CoatingKernel(**traced_mesh_fields(geometry, ladar, radiometry, samples, trace))
    if trace:
        raise ParameterError(f"trace options {sorted(trace)} apply to a mesh scene; this one "
                             "is analytic")
    if not all(hasattr(s, "axes") for s in geometry.shapes):
        raise ParameterError("coating_kernel takes analytic shapes (Disk, Ellipse), a mesh "
                             "Scene or mesh Hits")
    if not ladar.planar:
        raise ParameterError("an analytic scene's kernel needs views about the z axis; "
                             "this ladar has 3-D view vectors (trace a mesh instead)")
    samples = check_count("samples", 8192 if samples is None else samples)
    if samples > MAX_KERNEL_SAMPLES:
        raise ParameterError(f"samples must be at most {MAX_KERNEL_SAMPLES} per boundary "
                             f"(the kernel converges at second order well before); got "
                             f"{samples}")
    return CoatingKernel(**analytic_fields(geometry, ladar, radiometry, samples))
