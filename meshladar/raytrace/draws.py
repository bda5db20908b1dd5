"""numpy's ``default_rng([seed, i]).uniform(0, 1, n)`` draws for many views in one compiled
call, bit for bit: the seed sequence's hash of the entropy words
(``numpy.random.SeedSequence``: a pool of four 32-bit words, mixed, then eight words
generated from it), PCG64 (the 128-bit LCG with the XSL-RR output, numpy's
``default_rng``) seeded from those words, and doubles (x >> 11) · 2⁻⁵³. Building the
generator in numpy costs some 10 µs a view, more than a small view's planning; here it is
under half a µs (a run of many small stratified views draws every view's shifts so:
:func:`plans_sequences`). ``tests/raytrace/test_grid.py`` holds the draws to numpy's.

The 128-bit state is held as two uint64 halves (high, low); every constant is a uint64,
as numba would otherwise mix signed and unsigned integers into floats.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .grid import kronecker

__all__ = ["plans_sequences", "entropy_words", "view_uniforms"]

_U = np.uint64
_M32 = _U(0xFFFFFFFF)
_S16, _S32, _S11, _S58, _S63, _S1, _S64 = _U(16), _U(32), _U(11), _U(58), _U(63), _U(1), _U(64)
_ONE, _ZERO = _U(1), _U(0)
# SeedSequence's constants (numpy/random/bit_generator.pyx)
_INIT_A, _MULT_A = _U(0x43b0d7e5), _U(0x931e8875)
_INIT_B, _MULT_B = _U(0x8b51f9dd), _U(0x58f38ded)
_MIX_L, _MIX_R = _U(0xca01f9dd), _U(0x4973f715)
# PCG64's default multiplier (numpy/random/src/pcg64/pcg64.h), high and low halves
_MUL_HI, _MUL_LO = _U(2549297995355413924), _U(4865540595714422341)
_TO_UNIT = 1.0 / 9007199254740992.0                 # 2⁻⁵³


def plans_sequences(plans, views, seed):
    """The stratified offsets' sequences of many views' grids, each view's as
    :func:`meshladar.raytrace.grid.stratified_sequences` draws them from
    ``np.random.default_rng([seed, i])`` (the same bits), in one compiled call.

    Parameters
    ----------
    plans : meshladar.raytrace.grid.GridPlans
        The views' grids (:func:`meshladar.raytrace.grid.grid_plans`).
    views : (k,) array_like of int
        Each grid's view index i, which seeds its draws with ``seed``.
    seed : int or sequence of int
        The run's seed: a non-negative int or a sequence of them, as numpy takes it.

    Returns
    -------
    tuple of float32 numpy.ndarray
        (xi, ku, kv, eta): view j's ξ is ``xi[s_at[j]:s_at[j + 1]]`` and its η
        ``eta[t_at[j]:t_at[j + 1]]`` (packed as ``plans`` packs its centres); ku and kv
        are the centred Kronecker sequences of the longest rows and columns, whose starts
        serve every view.
    """
    xi, eta = np.empty(plans.s.size), np.empty(plans.t.size)
    view_uniforms(entropy_words(seed), np.asarray(views, dtype=np.int64), plans.s_at,
                  plans.t_at, xi, eta)
    ku = kronecker(int(np.max(np.diff(plans.t_at))))
    kv = kronecker(int(np.max(np.diff(plans.s_at))))
    return xi.astype(np.float32), ku, kv, eta.astype(np.float32)


def entropy_words(value):
    """The 32-bit words numpy's seed sequence makes of its entropy.

    Parameters
    ----------
    value : int or (nested) sequence of int
        Non-negative integers.

    Returns
    -------
    uint64 numpy.ndarray
        Each int's 32-bit words from the least significant ([0] for zero), a sequence's
        concatenated in order, as ``numpy.random.SeedSequence`` assembles its entropy.

    Raises
    ------
    ValueError
        For a negative int (numpy refuses them too).
    """
    if isinstance(value, (int, np.integer)):
        n, words = int(value), []
        if n < 0:
            raise ValueError(f"seed: entropy must be non-negative integers; got {n}")
        while True:
            words.append(n & 0xFFFFFFFF)
            n >>= 32
            if not n:
                return np.array(words, dtype=np.uint64)
    return np.concatenate([entropy_words(v) for v in value] or [np.zeros(0, np.uint64)])


@njit(cache=True, nogil=True)
def _hashmix(value, h):
    value = (value ^ h) & _M32
    h = (h * _MULT_A) & _M32
    value = (value * h) & _M32
    return value ^ (value >> _S16), h


@njit(cache=True, nogil=True)
def _mix(x, y):
    r = (_MIX_L * x - _MIX_R * y) & _M32
    return r ^ (r >> _S16)


@njit(cache=True, nogil=True)
def _pool(entropy):
    """SeedSequence.mix_entropy: the pool of four words from the entropy words."""
    pool = np.zeros(4, np.uint64)
    h = _INIT_A
    for i in range(4):
        pool[i], h = _hashmix(entropy[i] if i < entropy.size else _ZERO, h)
    for i_src in range(4):
        for i_dst in range(4):
            if i_src != i_dst:
                v, h = _hashmix(pool[i_src], h)
                pool[i_dst] = _mix(pool[i_dst], v)
    for i_src in range(4, entropy.size):
        for i_dst in range(4):
            v, h = _hashmix(entropy[i_src], h)
            pool[i_dst] = _mix(pool[i_dst], v)
    return pool


@njit(cache=True, nogil=True)
def _mulhi(x, y):
    """The high 64 bits of the 128-bit product x·y."""
    x0, x1, y0, y1 = x & _M32, x >> _S32, y & _M32, y >> _S32
    p00, p01, p10, p11 = x0 * y0, x0 * y1, x1 * y0, x1 * y1
    mid = (p00 >> _S32) + (p01 & _M32) + (p10 & _M32)
    return p11 + (p01 >> _S32) + (p10 >> _S32) + (mid >> _S32)


@njit(cache=True, nogil=True)
def _step(hi, lo, inc_hi, inc_lo):
    """state · multiplier + increment, modulo 2¹²⁸."""
    m_hi = _mulhi(lo, _MUL_LO) + hi * _MUL_LO + lo * _MUL_HI
    m_lo = lo * _MUL_LO
    n_lo = m_lo + inc_lo
    return m_hi + inc_hi + (_ONE if n_lo < m_lo else _ZERO), n_lo


@njit(cache=True, nogil=True)
def _seeded(entropy):
    """PCG64's state and increment from the seed sequence of ``entropy``: generate_state(4,
    uint64) (eight words, little-endian pairs), then pcg64_set_seed's srandom."""
    pool = _pool(entropy)
    word = np.zeros(8, np.uint64)
    h = _INIT_B
    for i in range(8):
        v = (pool[i % 4] ^ h) & _M32
        h = (h * _MULT_B) & _M32
        v = (v * h) & _M32
        word[i] = v ^ (v >> _S16)
    s_hi, s_lo = word[0] | (word[1] << _S32), word[2] | (word[3] << _S32)
    q_hi, q_lo = word[4] | (word[5] << _S32), word[6] | (word[7] << _S32)
    inc_hi, inc_lo = (q_hi << _S1) | (q_lo >> _S63), (q_lo << _S1) | _ONE
    hi, lo = _step(_ZERO, _ZERO, inc_hi, inc_lo)
    lo2 = lo + s_lo
    hi, lo = _step(hi + s_hi + (_ONE if lo2 < lo else _ZERO), lo2, inc_hi, inc_lo)
    return hi, lo, inc_hi, inc_lo


@njit(cache=True, nogil=True)
def _draw(out, a, b, hi, lo, inc_hi, inc_lo):
    """out[a:b] from the generator (step, then XSL-RR output, then 53 bits); its state."""
    for k in range(a, b):
        hi, lo = _step(hi, lo, inc_hi, inc_lo)
        x, r = hi ^ lo, hi >> _S58
        x = (x >> r) | (x << ((_S64 - r) & _S63))
        out[k] = np.float64(x >> _S11) * _TO_UNIT
    return hi, lo


@njit(cache=True, nogil=True)
def view_uniforms(seed_words, views, s_at, t_at, xi, eta):
    """Each view's ``default_rng([seed, views[j]]).uniform(0, 1, n)`` draws, in one call.

    Parameters
    ----------
    seed_words : uint64 numpy.ndarray
        :func:`entropy_words` of the seed.
    views : (k,) int64 numpy.ndarray
        The views' indices (non-negative).
    s_at, t_at : (k + 1,) int64 numpy.ndarray
        Where each view's draws go: view j's first s_at[j + 1] − s_at[j] draws into
        ``xi[s_at[j]:s_at[j + 1]]``, then its next t_at[j + 1] − t_at[j] into
        ``eta[t_at[j]:t_at[j + 1]]`` (the order of
        :func:`meshladar.raytrace.grid.stratified_sequences`).
    xi, eta : float64 numpy.ndarray
        Outputs, written where ``s_at`` and ``t_at`` say.
    """
    n = seed_words.size
    entropy = np.zeros(n + 2, np.uint64)
    entropy[:n] = seed_words
    for j in range(views.size):
        i = _U(views[j])                               # the view's words, as numpy's
        entropy[n] = i & _M32
        m = n + 1
        if i >> _S32:
            entropy[m] = i >> _S32
            m += 1
        hi, lo, inc_hi, inc_lo = _seeded(entropy[:m])
        hi, lo = _draw(xi, s_at[j], s_at[j + 1], hi, lo, inc_hi, inc_lo)
        _draw(eta, t_at[j], t_at[j + 1], hi, lo, inc_hi, inc_lo)
