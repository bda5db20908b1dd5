"""Deprecated alias of meshladar.waveforms (one release).

The pulses, :class:`Waveforms` and :func:`receive` live in :mod:`meshladar.waveforms`; the
receiver's :class:`Noise` and :func:`draw_noise` in :mod:`meshladar.noise`.
"""

from __future__ import annotations

from ._deprecated import warn_moved
from .noise import *  # noqa: F401,F403
from .noise import Noise, draw_noise
from .waveforms import *  # noqa: F401,F403
from .waveforms import GaussianPulse, SampledPulse, Waveforms, receive

warn_moved("receiver", "waveforms (and meshladar.noise for Noise)")

__all__ = ["GaussianPulse", "SampledPulse", "Noise", "Waveforms", "receive", "draw_noise"]
