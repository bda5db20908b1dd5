"""The coating kernel's discretisation error as a known, controlled quantity.

An analytic scene's kernel with N pieces per boundary errs by O(1/N²) (second order: the
change from N to 2N is ~3/4 of the N kernel's error and ~3× the 2N kernel's). A fit uses
the 2N kernel and reports, as its kernel error, the largest change |m_2N − m_N| of the
model at the estimate over the bins, in units of each bin's noise σ (an upper estimate of
the error of the kernel it used), and the largest shift of a parameter that change causes,
in its σ (many bins each under 0.1 σ may shift a parameter by more). The sample count
doubles until both are at most ``kernel_tol`` (default :data:`KERNEL_TOL` = 0.1), up to
``max_samples``.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..errors import MeshladarWarning

#: Largest kernel error allowed in any bin, in units of that bin's noise σ.
KERNEL_TOL = 0.1
#: The smallest kernel_tol taken (an error of a millionth of σ needs ~2^10 times the
#: pieces that 0.1 σ needs: beyond any cap).
MIN_KERNEL_TOL = 1e-6
#: Most pieces per boundary the refinement goes to (a 360-view kernel at 2^16 takes ~15 s
#: and ~1 GB).
MAX_SAMPLES = 2 ** 16


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
        self.error = self.shift = None

    @property
    def used(self):
        """The kernel the fit uses."""
        return self.coarse.resampled(2 * self.coarse.samples) if self.active else self.coarse

    def settle(self, mats, sigma_of, shift_of=None):
        """Double N until the kernel error with coatings ``mats`` is at most the tolerance
        (``sigma_of(kernel, mats)`` gives each bin's σ with that kernel), and so is the
        parameters' shift ``shift_of(coarse, fine)`` (in their σ) where given, or the cap
        is reached; True when the kernel used did not change."""
        if not self.active:
            return True
        before = self.used
        while True:
            fine = self.used
            self.error = kernel_error(self.coarse, fine, mats, sigma_of(fine, mats))
            self.shift = None if shift_of is None else shift_of(self.coarse, fine)
            worst = max(self.error, self.shift or 0.0)
            if worst <= self.tol or 2 * fine.samples > self.cap:
                break
            self.coarse = fine
        return self.used is before

    def warn_if_coarse(self):
        """Warn with the numbers when the cap stopped the refinement above tolerance."""
        if self.active and max(self.error, self.shift or 0.0) > self.tol:
            n = self.used.samples
            worst = max(self.error, self.shift or 0.0)
            need = n * 2 ** min(64, math.ceil(0.5 * math.log2(worst / self.tol)))
            warnings.warn(f"the coating kernel's error is {self.error:.3g} σ in its worst bin "
                          f"(a shift of {self.shift or 0.0:.3g} σ in the parameters) "
                          f"with {n} samples per boundary (kernel_tol={self.tol:g}, capped "
                          f"by max_samples={self.cap}); pass max_samples={need} (the error "
                          "falls ~4× per doubling) or accept it", KernelErrorWarning,
                          stacklevel=3)

    def info(self):
        """The kernel's resolution for the fit's ``info``."""
        if not self.active:
            return {"kernel_error": None, "samples": self.coarse.samples,
                    "kernel_error_note": "not estimated: " + (
                        "kernel_tol=None" if self.tol is None and self.coarse.samples
                        else f"a {self.coarse.source} kernel cannot be resampled (check it "
                             "against one traced at a finer spacing)")}
        return {"kernel_error": self.error, "kernel_shift": self.shift,
                "samples": self.used.samples,
                "kernel_error_note": f"largest |model({self.used.samples}) − "
                                     f"model({self.coarse.samples})| over the bins, in "
                                     "units of each bin's noise σ (an upper estimate of "
                                     "the error of the kernel used); kernel_shift: the largest shift of a "
                                     "parameter, in its σ, that change causes"}
