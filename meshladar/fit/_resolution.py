"""The coating kernel's discretisation error as a known, controlled quantity.

An analytic scene's kernel with N pieces per boundary errs by O(1/N²) (second order: the
change from N to 2N is ~3/4 of the N kernel's error and ~3× the 2N kernel's). A fit uses
the 2N kernel and reports, as its kernel error, the largest change |m_2N − m_N| of the
model at the estimate over the bins, in units of each bin's noise σ (an upper estimate of
the error of the kernel it used), and the largest shift of a parameter that change causes,
in its σ (many bins each under 0.1 σ may shift a parameter by more). The sample count
doubles until both are at most ``kernel_tol`` (default :data:`KERNEL_TOL` = 0.1), up to
``max_samples``. Stopped there, a :class:`KernelErrorWarning` gives the max_samples that
would do, never more than fit_coatings takes (``MAX_KERNEL_SAMPLES`` = 2^20); where even
that would not, the error expected there and the kernel_tol that accepts it.

A mesh kernel traced from its Scene climbs the same ladder in rays per range-bin width
(the scene traced again at half the ray spacing), up to :data:`MAX_KERNEL_RAYS` rays over
all views. Point binning converges slowly: near a silhouette or a range extremum the range
is quadratic in the ray's position, so a bin's share of rays errs at order 1/2 in the
spacing (measured on a glinting prism: a noiseless fit's offset falls ~N^-0.6, and the
change from N to 2N is a third to a quarter of the 2N kernel's own offset). Its change is
therefore scaled by :data:`MESH_ERROR_FACTOR` = 1/(√2 − 1), the error of the 2N kernel if
it converges at order 1/2 (Richardson), before it is compared or reported. A kernel
of the user's own Hits is not checked (its ``kernel_error`` is None and the note says so).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..errors import MeshladarWarning, user_stacklevel
from . import _irls
from ._params import _materials
from .kernels import MAX_KERNEL_SAMPLES

#: Largest kernel error allowed in any bin, in units of that bin's noise σ.
KERNEL_TOL = 0.1
#: The smallest kernel_tol taken (an error of a millionth of σ needs ~2^10 times the
#: pieces that 0.1 σ needs: beyond any cap).
MIN_KERNEL_TOL = 1e-6
#: Most pieces per boundary the refinement goes to (a 360-view kernel at 2^16 takes ~15 s
#: and ~1 GB).
MAX_SAMPLES = 2 ** 16
#: Most rays a mesh kernel's refinement traces over all views (the hits take ~60 bytes a
#: ray while the kernel is built: about 0.5 GB).
MAX_KERNEL_RAYS = 2 ** 23
#: A mesh kernel's error per unit of its change from N to 2N rays per bin width: the
#: Richardson factor 1/(2^p − 1) of convergence at order p = 1/2.
MESH_ERROR_FACTOR = 1.0 / (math.sqrt(2.0) - 1.0)


class KernelErrorWarning(MeshladarWarning):
    """A coating kernel's discretisation error is above the tolerance asked for."""


def kernel_error(coarse, fine, mats, sigma):
    """The largest |fine − coarse| / σ over the bins of the two kernels' models."""
    d = np.abs(fine.predict(mats) - coarse.predict(mats)).ravel()
    return float(np.max(d / np.broadcast_to(sigma, d.shape), initial=0.0))


class Ladder:
    """The kernels a fit climbs: ``coarse`` (N) against ``fine`` (2N), the fine one used."""

    def __init__(self, kernel, tol, cap):
        self.tol, self.cap = tol, cap
        self.active = (tol is not None and kernel.samples is not None
                       and kernel._traced is not None)
        self.coarse = kernel
        self.error = self.shift = self.step = None
        #: the kernel's error per unit of its change from N to 2N
        self.factor = MESH_ERROR_FACTOR if kernel.source == "mesh" else 1.0

    @property
    def used(self):
        """The kernel the fit uses."""
        return self.coarse.resampled(2 * self.coarse.samples) if self.active else self.coarse

    def settle(self, mats, sigma_of, shift_of=None):
        """Double N until the kernel error with coatings ``mats`` is at most the tolerance
        (``sigma_of(kernel, mats)`` gives each bin's σ with that kernel), and so is the
        parameters' largest shift ``shift_of(coarse, fine)`` (in their σ; with the shifts,
        kept scaled as ``step``) where given, or the cap is reached; True when the kernel
        used did not change."""
        if not self.active:
            return True
        before = self.used
        while True:
            fine = self.used
            self.error = self.factor * kernel_error(self.coarse, fine, mats,
                                                    sigma_of(fine, mats))
            if shift_of is not None:
                shift, step = shift_of(self.coarse, fine)
                self.shift, self.step = self.factor * shift, self.factor * step
            if self.worst <= self.tol or not self._refinable(fine):
                break
            self.coarse = fine
        return self.used is before

    @property
    def worst(self):
        """What must be within the tolerance: the per-bin error and the parameters' shift
        of an analytic kernel; a mesh kernel's shift alone (its per-bin error near a
        silhouette falls only ~N^-0.4, out of reach at 10⁵ photons in a bin, and a bin's
        error the parameters do not feel costs nothing; it is still reported)."""
        if self.coarse.source == "mesh":
            return self.shift or 0.0
        return max(self.error, self.shift or 0.0)

    def _refinable(self, kernel):
        """Whether the kernel at twice ``kernel``'s resolution is within the caps."""
        if 2 * kernel.samples > self.cap:
            return False
        return (kernel.source != "mesh"
                or kernel.rays * (2 if kernel.info["mode"] == "slice" else 4)
                <= MAX_KERNEL_RAYS)

    def warn_if_coarse(self):
        """Warn with the numbers when the cap stopped the refinement above tolerance."""
        if self.active and self.worst > self.tol:
            n, worst = self.used.samples, self.worst
            head = (f"the coating kernel's error is {self.error:.3g} σ in its worst bin "
                    f"(a shift of {self.shift or 0.0:.3g} σ in the parameters) ")
            if self.used.source == "mesh":
                need = n * 2 ** min(64, math.ceil(math.log2(worst / self.tol)))
                text = (f"with {n:.4g} rays per bin width ({self.used.rays} rays; "
                        f"kernel_tol={self.tol:g}, capped at {MAX_KERNEL_RAYS} rays or "
                        f"max_samples={self.cap}); about {need:.4g} rays per bin width would "
                        "do (the error falls ~2× per doubling): trace fewer views at a time, "
                        "or accept it")
            else:
                text = (f"with {n} samples per boundary (kernel_tol={self.tol:g}, capped by "
                        f"max_samples={self.cap}); " + _analytic_advice(n, worst, self.tol))
            warnings.warn(head + text, KernelErrorWarning, stacklevel=user_stacklevel())

    def info(self):
        """The kernel's resolution for the fit's ``info``."""
        if not self.active:
            return {"kernel_error": None, "samples": self.coarse.samples,
                    "kernel_error_note": "not estimated: " + (
                        "kernel_tol=None" if self.tol is None and self.coarse.samples
                        else f"a kernel of {self.coarse.source} hits cannot be resampled "
                             "(give fit_coatings the mesh Scene, or coating_kernel(scene, "
                             "ladar), to have it traced and checked at finer spacings)")}
        return {"kernel_error": self.error, "kernel_shift": self.shift,
                "samples": self.used.samples,
                "kernel_error_note": (f"largest |model({self.used.samples:g}) − "
                                      f"model({self.coarse.samples:g})| "
                                      f"({_unit(self.used)}) over the bins, in units of "
                                      "each bin's noise σ" + (
                                          f", times {self.factor:.3g} (convergence at "
                                          "order 1/2)" if self.factor != 1.0 else
                                          " (an upper estimate of the error of the kernel "
                                          "used)") + "; kernel_shift: the largest shift of "
                                      "a parameter, in its σ, that change causes (scaled "
                                      "alike)")}


def _analytic_advice(n, worst, tol):
    """What to do about an analytic kernel of ``n`` samples per boundary whose error (or
    shift) ``worst`` exceeds ``tol``: the max_samples that would do (the error falls ~4×
    per doubling), never beyond what fit_coatings takes (:data:`MAX_KERNEL_SAMPLES`); past
    it, the error expected there and how to accept it."""
    need = n * 2 ** min(64, math.ceil(0.5 * math.log2(worst / tol)))
    if need <= MAX_KERNEL_SAMPLES:
        return f"pass max_samples={need} (the error falls ~4× per doubling) or accept it"
    if n >= MAX_KERNEL_SAMPLES:
        return (f"this is the most max_samples takes ({MAX_KERNEL_SAMPLES}): accept it "
                f"(kernel_tol={_up(worst)} allows it; kernel_tol=None skips the check)")
    there = worst / 4.0 ** math.log2(MAX_KERNEL_SAMPLES / n)
    return (f"even the most max_samples takes, {MAX_KERNEL_SAMPLES}, leaves about "
            f"{there:.2g} σ (the error falls ~4× per doubling): pass "
            f"max_samples={MAX_KERNEL_SAMPLES} with kernel_tol={_up(there)}, or accept it "
            "(kernel_tol=None skips the check)")


def _up(value):
    """``value`` rounded up to two significant digits, as text."""
    digits = math.floor(math.log10(value)) - 1
    return f"{math.ceil(value / 10.0 ** digits) * 10.0 ** digits:.2g}"


def _unit(kernel):
    """What a kernel's ``samples`` counts."""
    return "rays per bin width" if kernel.source == "mesh" else "pieces per boundary"


def kernel_shift(model, at, coarse, fine):
    """(the largest shift of a parameter in its σ, the shifts) that the model's change
    from the ``coarse`` to the ``fine`` kernel causes at ``at`` = (x, model values)."""
    step, sd = kernel_step(model, at, coarse, fine)
    ok = sd > 0
    return float(np.max(np.abs(step[ok]) / sd[ok], initial=0.0)), step


def kernel_step(model, at, coarse, fine):
    """(the parameters' shift, their σ) that the model's change Δm from the ``coarse`` to
    the ``fine`` kernel causes at ``at`` = (x, model values): the weighted least-squares
    step (Jᵀ W J)⁺ Jᵀ W Δm, W the inverse noise variance."""
    problem = model.problem
    x, m = at
    mats = _materials(problem.mats, problem.params, x)
    dm = (fine.predict(mats) - coarse.predict(mats)).ravel()[problem.rows] * problem.scale
    if problem.noise == "gaussian":
        rss = float(np.sum((problem.data - m) ** 2)) / max(1, m.size - len(x))
        w = np.full(m.size, 1.0 / math.sqrt(max(rss, 1e-300)))
    else:
        w = 1.0 / np.sqrt(_irls.variance(m, problem.noise, problem.M))
    Jw = model.jacobian(x) * w[:, None]
    cov = np.linalg.pinv(Jw.T @ Jw)
    return cov @ (Jw.T @ (dm * w)), np.sqrt(np.maximum(np.diag(cov), 0.0))


def with_kernel_error(covariance, step):
    """The covariance with the kernel's estimated error added as a systematic term
    s sᵀ (s the parameters' shift from N to 2N), on the determined parameters."""
    ok = np.isfinite(np.diag(covariance)) & np.isfinite(step)
    out = covariance.copy()
    out[np.ix_(ok, ok)] += np.outer(step[ok], step[ok])
    return out
