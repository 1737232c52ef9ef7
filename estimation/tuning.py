"""Gain helpers shared by the observers: second-order response times and Levant's coefficients.

The change-of-coordinates observers (thesis 4.3, 4.4; ECC'15 eq. 18-20; seed 001 eq. 11-13)
place the poles of each output's error dynamics at ``s^2 + 2 xi omega s + omega^2``, i.e.
``K1 = 2 xi omega`` and ``K2 = omega^2``. The thesis tunes them by a 5 % response time and a
damping (chapter 5.2.1: 6 s and 0.8); :func:`omega_for_settling_time` turns that pair into
``omega`` exactly (5 % settling time of the second-order step response).
"""
from __future__ import annotations

import functools
import math

import numpy as np

__all__ = ["settling_time_normalised", "omega_for_settling_time", "LEVANT_A1", "LEVANT_A2"]

#: Levant's robust exact differentiator coefficients used by the seeds (thesis 4.48, ECC'15 eq. 23).
LEVANT_A1 = 1.5
LEVANT_A2 = 1.1


@functools.lru_cache(maxsize=64)
def settling_time_normalised(damping: float) -> float:
    """``omega * t_5%`` of ``s^2 + 2 xi omega s + omega^2`` (unit step, 5 % band), for ``0 < xi < 1``.

    The step response is ``1 - exp(-xi tau) (cos(wd tau) + xi/wd sin(wd tau))`` with
    ``tau = omega t`` and ``wd = sqrt(1 - xi^2)``; the 5 % time is the last exit from the band,
    found on a fine grid (1e-4 in tau).
    """
    if not (isinstance(damping, (int, float)) and 0.0 < damping < 1.0):
        raise ValueError(f"damping must lie in (0, 1), got {damping!r}")
    tau = np.arange(0.0, 200.0, 1e-4)
    wd = math.sqrt(1.0 - damping * damping)
    response = 1.0 - np.exp(-damping * tau) * (np.cos(wd * tau) + damping / wd * np.sin(wd * tau))
    outside = np.nonzero(np.abs(1.0 - response) > 0.05)[0]
    return float(tau[outside[-1] + 1])


def omega_for_settling_time(settling_time_s: float, damping: float) -> float:
    """Natural frequency (rad/s) giving a 5 % response time ``settling_time_s`` at ``damping``.

    Parameters
    ----------
    settling_time_s : float
        Time to enter and stay in the 5 % band of a step response, seconds.
    damping : float
        Damping ratio of the second-order response.

    Returns
    -------
    float
        rad/s.
    """
    if not (isinstance(settling_time_s, (int, float)) and math.isfinite(settling_time_s) and settling_time_s > 0):
        raise ValueError(f"settling_time_s must be a positive number of seconds, got {settling_time_s!r}")
    return settling_time_normalised(float(damping)) / settling_time_s
