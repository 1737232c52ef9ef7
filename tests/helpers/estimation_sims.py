"""Simulated approaches shared by the estimation tests (computed once per test session)."""
from __future__ import annotations

import functools

import numpy as np

from visland.estimation.inputs import FeatureSeries, InertialSeries, prepare_inputs
from visland.scenarios import get_scenario
from visland.sensors import ImuParams
from visland.simulate import SimulationOptions, run_simulation


@functools.lru_cache(maxsize=8)
def simulation(scenario: str = "thesis-1", pixel_noise_px: float = 0.0, seed: int = 0, velocity_bias: float = 0.0):
    options = SimulationOptions(pixel_noise_px=pixel_noise_px, seed=seed,
                                imu=ImuParams(velocity_bias_fraction=velocity_bias))
    return run_simulation(get_scenario(scenario), options)


@functools.lru_cache(maxsize=8)
def prepared(scenario: str = "thesis-1", pixel_noise_px: float = 0.0, seed: int = 0, velocity_bias: float = 0.0):
    result = simulation(scenario, pixel_noise_px, seed, velocity_bias)
    return prepare_inputs(InertialSeries.from_imu(result.imu), FeatureSeries.from_ideal(result.features),
                          result.options.camera)


def true_virtual_points(result, states=None) -> np.ndarray:
    """Virtual coordinates of P' and P'' straight from the flown positions (thesis 3.23 by geometry)."""
    p = (states or result.frames).p_runway_m
    corners = result.scenario.runway.corners_runway_m()[:2]
    return (corners[None, :, :2] - p[:, None, :2]) / (-p[:, None, 2:3])


def true_height(result) -> np.ndarray:
    return -result.frames.p_runway_m[:, 2]


def random_line_inputs(rng):
    """Plausible approach inputs for the line model, as ``lines_model.inputs_of`` orders them:
    camera velocity (70-80 m/s along the optical axis), small rates, the runway down axis near
    the image y axis, then the vertical velocity."""
    v = np.array([rng.normal(0, 5), rng.normal(0, 5), rng.uniform(65, 80)])
    w = rng.normal(0, 0.05, 3)
    n = np.array([rng.normal(0, 0.1), 1.0, rng.uniform(0.0, 0.3)])
    n /= np.linalg.norm(n)
    return tuple(v) + tuple(w) + tuple(n) + (rng.uniform(-1, 5),)

