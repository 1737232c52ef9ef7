"""Flight simulation at 50 Hz: a stabilised airliner under ILS-like landing guidance.

Aircraft model (thesis hypothesis 7 and section 5.1.1: "avion stabilisé")
----------------------------------------------------------------------------
Point-mass kinematics with the flight-control loops closed:

- constant airspeed ``V`` (autothrottle, hypothesis 5);
- longitudinal: the load factor ``nz`` follows its order through a second order,
  ``nz'' = w^2 (nz_c - nz) - 2 xi w nz'`` with ``w = 1.25 rad/s``, ``xi = 0.7``;
  flight path ``gamma' = (g / V) (nz cos(mu) - cos(gamma))``;
- lateral: the bank ``mu`` follows its order as a first order, ``mu' = (mu_c - mu) / 1.5 s``,
  with the bank rate limited to 11.5 deg/s so that the Euler roll rate stays inside the
  12 deg/s of thesis 1.3.2;
- coordinated turn: ``chi' = g nz sin(mu) / (V cos(gamma))``, no sideslip;
- angle of attack from the load factor at constant speed: ``alpha = alpha_0 + (alpha_1g -
  alpha_0) nz``; the body is the wind frame pitched up by alpha:
  ``R_ned_from_body = Rz(chi) Ry(gamma) Rx(mu) Ry(alpha)``.
- ground velocity = air velocity + wind (steady crosswind and a Dickmanns gust, optional).

Guidance (an ILS autopilot flown on true position: LOC and G/S capture and track)
---------------------------------------------------------------------------------
- lateral: lateral speed order ``y'_c = -V sin(chi_int) tanh(k_y dY / (V sin(chi_int)))``
  (intercept at most ``chi_int`` = 22 deg, linear near the centreline; a steeper intercept
  would turn the runway out of the camera's 45 deg field of view), lateral
  acceleration ``a_c = k_v (y'_c - y')``, bank order ``mu_c = atan(a_c / (g cos chi_r))``
  limited to 25 deg (autopilot bank limit; the structural limit of thesis 1.3.2 is 66 deg);
- vertical: from below the glide path in level flight, altitude hold until the glide-slope
  order becomes a descent (capture from below, as an ILS autopilot arms G/S, also when
  already descending below the path); then the
  vertical speed order ``h'_c = h'_gp - k_h dGS`` (``h'_gp`` the glide-path descent rate at
  the current ground speed) becomes a flight-path order limited to [-5.6, 10] deg (limit of
  thesis 1.3.2: -6 < gamma < 20 deg) and a load-factor order
  ``nz_c = cos(gamma)/cos(mu) + (V/g) k_gamma (gamma_c - gamma)`` limited to [0.8, 1.25] g.

The run ends when the aircraft crosses the threshold (x_R >= 0, about 55 ft on the glide
path), so the seeds' 400/200/100 ft metrics exist on every approach.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from visland.frames import R_ned_from_runway
from visland.runway import GLIDE_SLOPE_RAD
from visland.scenarios import Scenario, Wind

__all__ = ["AircraftParams", "GuidanceParams", "Trajectory", "FrameStates", "simulate_flight", "FlareParams",
           "FlightModel", "AircraftState",
           "FLIGHT_LIMITS", "G_MPS2"]

G_MPS2 = 9.80665
FT_TO_M = 0.3048

#: Limits of thesis 1.3.2 checked on every trajectory.
FLIGHT_LIMITS = {
    "gamma_deg": (-6.0, 20.0),
    "nz_g": (-1.0, 2.5),  # the thesis prints "1 < Nz < 2.5"; a steady 3 deg descent alone has nz = cos 3 deg < 1,
                          # so the transport-category envelope -1 .. 2.5 g is meant
    "roll_rate_dps": (-12.0, 12.0),
    "roll_deg": (-66.0, 66.0),
}


@dataclass(frozen=True)
class AircraftParams:
    """Stabilised aircraft (thesis hypothesis 7) and its flight-control limits.

    Attributes
    ----------
    nz_omega_rad_s, nz_damping : float
        Natural frequency (rad/s) and damping of the load factor's second-order response.
    roll_time_constant_s : float
        Time constant of the bank's first-order response, seconds.
    roll_rate_limit_dps : float
        Bank-rate limit, deg/s (keeps the Euler roll rate under thesis 1.3.2's 12 deg/s).
    alpha_1g_deg, alpha_zero_lift_deg : float
        Angle of attack at 1 g and at zero lift, degrees (alpha linear in the load factor).
    """

    nz_omega_rad_s: float = 1.25
    nz_damping: float = 0.7
    roll_time_constant_s: float = 1.5
    roll_rate_limit_dps: float = 11.5  # bank-rate limit; keeps the Euler roll rate under the 12 deg/s of thesis 1.3.2
    alpha_1g_deg: float = 5.5
    alpha_zero_lift_deg: float = -2.0

    def __post_init__(self):
        for name in ("nz_omega_rad_s", "nz_damping", "roll_time_constant_s", "roll_rate_limit_dps"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"aircraft {name} must be positive, got {value!r}")


@dataclass(frozen=True)
class GuidanceParams:
    """Landing guidance gains and autopilot limits (see module docstring).

    Attributes
    ----------
    glide_slope_deg : float
        Glide path angle, degrees.
    intercept_angle_deg : float
        Largest localizer intercept angle ``chi_int``, degrees.
    k_y_per_s, k_v_per_s : float
        Lateral position and lateral speed gains, 1/s.
    bank_limit_deg : float
        Autopilot bank limit, degrees.
    k_h_per_s, k_gamma_per_s, k_alt_per_s : float
        Glide-path, flight-path and altitude-hold gains, 1/s.
    gamma_min_deg, gamma_max_deg : float
        Limits of the flight-path order, degrees.
    nz_min_g, nz_max_g : float
        Limits of the load-factor order, g.
    """

    glide_slope_deg: float = 3.0
    intercept_angle_deg: float = 22.0  # steeper intercepts swing the runway out of the 45 deg field of view
    k_y_per_s: float = 0.16
    k_v_per_s: float = 0.35
    bank_limit_deg: float = 25.0
    k_h_per_s: float = 0.25
    k_gamma_per_s: float = 0.3
    k_alt_per_s: float = 0.2
    gamma_min_deg: float = -5.6  # flight-path order floor; the overshoot stays above the -6 deg limit
    gamma_max_deg: float = 10.0
    nz_min_g: float = 0.8
    nz_max_g: float = 1.25

    def __post_init__(self):
        for name in ("intercept_angle_deg", "k_y_per_s", "k_v_per_s", "bank_limit_deg", "k_h_per_s",
                     "k_gamma_per_s", "k_alt_per_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"guidance {name} must be positive, got {value!r}")
        if not -6.0 < self.gamma_min_deg < 0.0:
            raise ValueError(f"guidance gamma_min_deg must lie in (-6, 0), got {self.gamma_min_deg}")
        if not 0.0 < self.nz_min_g < 1.0 < self.nz_max_g <= 2.5:
            raise ValueError("guidance nz limits must satisfy 0 < nz_min_g < 1 < nz_max_g <= 2.5")


def _wind_runway_mps(wind: Wind, t: float, crosswind_t0: float | None, gust_t0: float | None):
    """Wind velocity in the runway frame (x along the runway, y right, z down) at time t."""
    wx = wy = wz = 0.0
    if crosswind_t0 is not None:
        wx -= wind.headwind_mps
        wy += wind.crosswind_mps
    if gust_t0 is not None and t >= gust_t0:
        decay = math.exp(-(t - gust_t0) / wind.gust_time_constant_s)
        wy += wind.gust_crosswind_mps * decay
        wz -= wind.gust_updraft_mps * decay
    return wx, wy, wz


@dataclass
class Trajectory:
    """A flown approach sampled at the simulation rate.

    Arrays have one row per sample (``n``). Positions are of the aircraft centre of gravity,
    which carries the camera (thesis hypothesis 11).

    Attributes
    ----------
    scenario : Scenario
        What was flown.
    rate_hz : float
        Sampling (and integration) rate, Hz.
    t_s : (n,) time from the start of the vision-based approach.
    p_ned_m, p_runway_m : (n, 3) position in N and R (origin at the threshold centre).
    v_ned_mps, v_runway_mps : (n, 3) ground velocity.
    roll_rad, pitch_rad, heading_rad : (n,) ZYX Euler angles of the body from N.
    dpsi_rad : (n,) heading deviation ``heading - runway heading`` wrapped to [-pi, pi).
    omega_body_rps : (n, 3) body angular rates (p, q, r).
    gamma_rad, chi_rad, nz_g, alpha_rad : (n,) flight path, air-track heading, load factor, AoA.
    roll_rate_rps : (n,) Euler roll rate, rad/s (checked against thesis 1.3.2's 12 deg/s).
    bank_cmd_rad, nz_cmd_g : (n,) guidance orders at each sample.
    wind_ned_mps : (n, 3) wind velocity.
    end_reason : str
        Why the run ended (the threshold crossed, or the time limit).
    """

    scenario: Scenario
    rate_hz: float
    t_s: np.ndarray
    p_ned_m: np.ndarray
    v_ned_mps: np.ndarray
    roll_rad: np.ndarray
    pitch_rad: np.ndarray
    heading_rad: np.ndarray
    omega_body_rps: np.ndarray
    gamma_rad: np.ndarray
    chi_rad: np.ndarray
    nz_g: np.ndarray
    alpha_rad: np.ndarray
    roll_rate_rps: np.ndarray
    bank_cmd_rad: np.ndarray
    nz_cmd_g: np.ndarray
    wind_ned_mps: np.ndarray
    end_reason: str = ""
    R_runway_from_ned: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        self.R_runway_from_ned = R_ned_from_runway(self.scenario.runway.heading_rad).T

    @property
    def runway(self):
        return self.scenario.runway

    @property
    def p_runway_m(self) -> np.ndarray:
        return self.p_ned_m @ self.R_runway_from_ned.T

    @property
    def v_runway_mps(self) -> np.ndarray:
        return self.v_ned_mps @ self.R_runway_from_ned.T

    @property
    def dpsi_rad(self) -> np.ndarray:
        d = self.heading_rad - self.runway.heading_rad
        return (d + np.pi) % (2 * np.pi) - np.pi

    @property
    def dx_m(self) -> np.ndarray:
        return self.p_runway_m[:, 0] - self.runway.aim_distance_m

    @property
    def dy_m(self) -> np.ndarray:
        return self.p_runway_m[:, 1]

    @property
    def dh_m(self) -> np.ndarray:
        return -self.p_runway_m[:, 2]

    @property
    def dgs_m(self) -> np.ndarray:
        return self.dh_m + self.dx_m * math.tan(GLIDE_SLOPE_RAD)

    @property
    def duration_s(self) -> float:
        return float(self.t_s[-1] - self.t_s[0])

    def index_at_height(self, height_m: float) -> int | None:
        """First sample at which dH falls to ``height_m`` or below (None if it never does)."""
        below = np.nonzero(self.dh_m <= height_m)[0]
        return int(below[0]) if below.size else None

    def limits_report(self) -> dict:
        """Extremes of the constrained quantities and whether thesis 1.3.2 limits hold."""
        values = {
            "gamma_deg": np.degrees(self.gamma_rad),
            "nz_g": self.nz_g,
            "roll_rate_dps": np.degrees(self.roll_rate_rps),
            "roll_deg": np.degrees(self.roll_rad),
        }
        report = {}
        for name, series in values.items():
            low, high = FLIGHT_LIMITS[name]
            report[name] = {"min": float(series.min()), "max": float(series.max()),
                            "limits": [low, high],
                            "ok": bool(series.min() > low - 1e-9 and series.max() < high + 1e-9)}
        return report

    def at(self, times_s) -> "FrameStates":
        """States at arbitrary times inside the run, interpolated linearly between samples.

        Exact at sample times. Positions, velocities, unwrapped Euler angles and body rates
        are interpolated; within a 20 ms step the error is far below a millimetre.
        """
        times = np.asarray(times_s, dtype=float)
        if times.ndim != 1:
            raise ValueError("times_s must be one-dimensional")
        if times.size and (times.min() < self.t_s[0] - 1e-9 or times.max() > self.t_s[-1] + 1e-9):
            raise ValueError(f"times_s must lie in [{self.t_s[0]:g}, {self.t_s[-1]:g}] s")

        def interp(series):
            series = np.asarray(series)
            if series.ndim == 1:
                return np.interp(times, self.t_s, series)
            return np.stack([np.interp(times, self.t_s, series[:, k]) for k in range(series.shape[1])], axis=1)

        return FrameStates(
            t_s=times,
            p_runway_m=interp(self.p_runway_m),
            v_ned_mps=interp(self.v_ned_mps),
            v_runway_mps=interp(self.v_runway_mps),
            roll_rad=interp(np.unwrap(self.roll_rad)),
            pitch_rad=interp(self.pitch_rad),
            heading_rad=interp(np.unwrap(self.heading_rad)),
            dpsi_rad=interp(np.unwrap(self.dpsi_rad)),
            omega_body_rps=interp(self.omega_body_rps),
        )


@dataclass
class FrameStates:
    """Aircraft states at camera frame times (see :meth:`Trajectory.at`), truth in SI units.

    Attributes
    ----------
    t_s : ndarray, shape (n,)
        Frame times, seconds.
    p_runway_m : ndarray, shape (n, 3)
        Camera (centre of gravity) position in the runway frame R, metres.
    v_ned_mps, v_runway_mps : ndarray, shape (n, 3)
        Ground velocity in NED and in R, m/s.
    roll_rad, pitch_rad, heading_rad : ndarray, shape (n,)
        ZYX Euler angles of the body from NED, radians.
    dpsi_rad : ndarray, shape (n,)
        Heading minus runway heading, radians, in [-pi, pi).
    omega_body_rps : ndarray, shape (n, 3)
        Body rates (p, q, r), rad/s.
    """

    t_s: np.ndarray
    p_runway_m: np.ndarray
    v_ned_mps: np.ndarray
    v_runway_mps: np.ndarray
    roll_rad: np.ndarray
    pitch_rad: np.ndarray
    heading_rad: np.ndarray
    dpsi_rad: np.ndarray
    omega_body_rps: np.ndarray

    def __len__(self):
        return len(self.t_s)


class _Guidance:
    """ILS-like autopilot with its capture logic (state: the vertical mode)."""

    def __init__(self, params: GuidanceParams, scenario: Scenario, airspeed_mps: float):
        self.p = params
        self.V = airspeed_mps
        self.tan_gs = math.tan(math.radians(params.glide_slope_deg))
        self.aim_m = scenario.runway.aim_distance_m
        self.vertical_mode = "ALT" if scenario.dgs_m < 0.0 else "GS"
        self.altitude_hold_m = scenario.initial_height_m
        self.gamma_min = math.radians(params.gamma_min_deg)
        self.gamma_max = math.radians(params.gamma_max_deg)
        self.bank_limit = math.radians(params.bank_limit_deg)
        self.saturated = ()
        self.v_intercept_fraction = math.sin(math.radians(params.intercept_angle_deg))

    def update_mode(self, p_runway, v_runway):
        """Arm the glide-slope mode once its order turns to a descent (called once per step)."""
        if self.vertical_mode == "ALT":
            dgs = -p_runway[2] + (p_runway[0] - self.aim_m) * self.tan_gs
            if -v_runway[0] * self.tan_gs - self.p.k_h_per_s * dgs <= 0.0:
                self.vertical_mode = "GS"

    def orders(self, p_runway, v_runway, gamma, mu):
        """Bank order (rad) and load-factor order (g) from the true position and velocity.

        A continuous function of the state (the vertical mode only changes between steps), so
        the orders can be evaluated at every integration stage and the attitude rates are
        continuous: the inertial unit's rates are the derivative of the attitude flown.
        """
        p = self.p
        x, y, z = p_runway
        vx, vy, vz = v_runway
        # lateral: LOC capture and track
        v_ground = math.hypot(vx, vy)
        v_int = max(v_ground * self.v_intercept_fraction, 1.0)
        ydot_cmd = -v_int * math.tanh(p.k_y_per_s * y / v_int)
        a_cmd = p.k_v_per_s * (ydot_cmd - vy)
        track_rel = math.atan2(vy, vx)
        bank_cmd = math.atan2(a_cmd, G_MPS2 * max(math.cos(track_rel), 0.2))
        saturated = []
        if abs(bank_cmd) > self.bank_limit:
            saturated.append(f"bank order at its {p.bank_limit_deg:g} deg limit")
        bank_cmd = max(-self.bank_limit, min(self.bank_limit, bank_cmd))
        # vertical: G/S capture (from below: altitude hold until the order turns to a descent)
        dx = x - self.aim_m
        dh = -z
        dgs = dh + dx * self.tan_gs
        hdot_gp = -vx * self.tan_gs
        hdot_cmd = hdot_gp - p.k_h_per_s * dgs
        if self.vertical_mode == "ALT":
            hdot_cmd = p.k_alt_per_s * (self.altitude_hold_m - dh)
        gamma_cmd = math.asin(max(-0.5, min(0.5, hdot_cmd / self.V)))
        if gamma_cmd < self.gamma_min:
            saturated.append(f"flight-path order at its {p.gamma_min_deg:g} deg floor")
        elif gamma_cmd > self.gamma_max:
            saturated.append(f"flight-path order at its {p.gamma_max_deg:g} deg ceiling")
        gamma_cmd = max(self.gamma_min, min(self.gamma_max, gamma_cmd))
        nz_cmd = math.cos(gamma) / math.cos(mu) + self.V / G_MPS2 * p.k_gamma_per_s * (gamma_cmd - gamma)
        if not p.nz_min_g <= nz_cmd <= p.nz_max_g:
            saturated.append(f"load-factor order at its {p.nz_min_g if nz_cmd < p.nz_min_g else p.nz_max_g:g} g limit")
        nz_cmd = max(p.nz_min_g, min(p.nz_max_g, nz_cmd))
        self.saturated = tuple(saturated)      # the autopilot limits that bound these orders
        return bank_cmd, nz_cmd


def simulate_flight(scenario: Scenario, aircraft: AircraftParams | None = None,
                    guidance: GuidanceParams | None = None, rate_hz: float = 50.0,
                    max_duration_s: float = 400.0) -> Trajectory:
    """Fly ``scenario`` from its initial conditions to the threshold.

    Integrates the model of the module docstring with a fixed-step RK4 at ``rate_hz``, the
    guidance orders evaluated at every stage (so attitude rates are continuous and the
    recorded body rates are the derivative of the attitude flown), and returns the sampled
    :class:`Trajectory`.

    Parameters
    ----------
    scenario : Scenario
        Initial conditions, runway and wind.
    aircraft : AircraftParams, optional
        The aircraft's responses and limits (default values of the module docstring).
    guidance : GuidanceParams, optional
        The ILS laws' gains and limits.
    rate_hz : float, default 50
        Integration and sampling rate, Hz, in [10, 1000].
    max_duration_s : float, default 400
        The run stops here if the threshold has not been crossed, seconds.

    Returns
    -------
    Trajectory
    """
    aircraft = aircraft or AircraftParams()
    guidance_params = guidance or GuidanceParams()
    if not (math.isfinite(rate_hz) and 10.0 <= rate_hz <= 1000.0):
        raise ValueError(f"rate_hz must lie in [10, 1000], got {rate_hz!r}")
    dt = 1.0 / rate_hz
    V = scenario.airspeed_mps
    guide = _Guidance(guidance_params, scenario, V)
    wind = scenario.wind
    R_ned_from_rwy = R_ned_from_runway(scenario.runway.heading_rad)
    R_rwy_from_ned = R_ned_from_rwy.T
    psi_rwy = scenario.runway.heading_rad

    w_nz = aircraft.nz_omega_rad_s
    xi_nz = aircraft.nz_damping
    tau_roll = aircraft.roll_time_constant_s
    roll_rate_max = math.radians(aircraft.roll_rate_limit_dps)

    # initial state: [n, e, d, gamma, chi, mu, nz, nzdot]
    p0_runway = np.array([scenario.runway.aim_distance_m + scenario.dx_m, scenario.dy_m,
                          -scenario.initial_height_m])
    p0_ned = R_ned_from_rwy @ p0_runway
    gamma0 = math.radians(scenario.gamma_deg)
    mu0 = math.radians(scenario.roll_deg)
    state = [float(p0_ned[0]), float(p0_ned[1]), float(p0_ned[2]), gamma0,
             psi_rwy + math.radians(scenario.dpsi_deg), mu0,
             math.cos(gamma0) / math.cos(mu0), 0.0]

    r = R_rwy_from_ned
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = (float(v) for v in r.ravel())
    q = R_ned_from_rwy
    q00, q01, q02, q10, q11, q12, q20, q21, q22 = (float(v) for v in q.ravel())

    # times at which the steady wind and the gust start (set when their onset distance is crossed)
    crosswind_t0 = 0.0 if wind.crosswind_onset_m is None else None
    gust_t0 = None

    def wind_ned(t):
        wx, wy, wz = _wind_runway_mps(wind, t, crosswind_t0, gust_t0)
        return (q00 * wx + q01 * wy + q02 * wz, q10 * wx + q11 * wy + q12 * wz, q20 * wx + q21 * wy + q22 * wz)

    def kinematics(t, s):
        """Position and ground velocity in the runway frame, ground velocity in NED, wind."""
        n_, e_, d_, gamma, chi = s[0], s[1], s[2], s[3], s[4]
        wn, we, wd = wind_ned(t)
        cg = math.cos(gamma)
        vn = V * cg * math.cos(chi) + wn
        ve = V * cg * math.sin(chi) + we
        vd = -V * math.sin(gamma) + wd
        p_rwy = (r00 * n_ + r01 * e_ + r02 * d_, r10 * n_ + r11 * e_ + r12 * d_, r20 * n_ + r21 * e_ + r22 * d_)
        v_rwy = (r00 * vn + r01 * ve + r02 * vd, r10 * vn + r11 * ve + r12 * vd, r20 * vn + r21 * ve + r22 * vd)
        return p_rwy, v_rwy, (vn, ve, vd), (wn, we, wd)

    def derivative(t, s):
        """State derivative with the guidance orders evaluated at this very state (and the orders)."""
        _, _, _, gamma, chi, mu, nz, nzdot = s
        p_rwy, v_rwy, (vn, ve, vd), _ = kinematics(t, s)
        bank_cmd, nz_cmd = guide.orders(p_rwy, v_rwy, gamma, mu)
        cg = math.cos(gamma)
        gamma_dot = G_MPS2 / V * (nz * math.cos(mu) - cg)
        chi_dot = G_MPS2 * nz * math.sin(mu) / (V * cg)
        mu_dot = max(-roll_rate_max, min(roll_rate_max, (bank_cmd - mu) / tau_roll))
        nz_ddot = w_nz * w_nz * (nz_cmd - nz) - 2.0 * xi_nz * w_nz * nzdot
        return (vn, ve, vd, gamma_dot, chi_dot, mu_dot, nzdot, nz_ddot), (bank_cmd, nz_cmd)

    n_max = int(max_duration_s * rate_hz) + 1
    rows = []          # state at each sample
    rates = []         # (gamma_dot, chi_dot, mu_dot, nzdot) at each sample with its held orders
    orders = []
    winds = []
    t = 0.0
    end_reason = "max_duration"
    for k in range(n_max):
        x_r = r00 * state[0] + r01 * state[1] + r02 * state[2]
        # onsets and modes change only between steps, so each step integrates a smooth field
        if wind.crosswind_onset_m is not None and crosswind_t0 is None and -x_r <= wind.crosswind_onset_m:
            crosswind_t0 = t
        if wind.gust and gust_t0 is None and -x_r <= wind.gust_onset_m:
            gust_t0 = t
        p_rwy, v_rwy, _, w_ned = kinematics(t, state)
        guide.update_mode(p_rwy, v_rwy)
        k1, order = derivative(t, state)
        rows.append(tuple(state))
        rates.append((k1[3], k1[4], k1[5], k1[6]))
        orders.append(order)
        winds.append(w_ned)
        if x_r >= 0.0:
            end_reason = "threshold"
            break
        if -p_rwy[2] < 2.0:
            end_reason = "ground"
            break
        half = 0.5 * dt
        k2, _ = derivative(t + half, [s + half * d for s, d in zip(state, k1)])
        k3, _ = derivative(t + half, [s + half * d for s, d in zip(state, k2)])
        k4, _ = derivative(t + dt, [s + dt * d for s, d in zip(state, k3)])
        state = [s + dt / 6.0 * (a + 2.0 * b + 2.0 * c + e)
                 for s, a, b, c, e in zip(state, k1, k2, k3, k4)]
        t = (k + 1) * dt

    S = np.array(rows)
    Rt = np.array(rates)
    O = np.array(orders)
    W = np.array(winds)
    n = len(S)
    t_s = np.arange(n) * dt
    gamma, chi, mu, nz, nzdot = S[:, 3], S[:, 4], S[:, 5], S[:, 6], S[:, 7]
    gamma_dot, chi_dot, mu_dot, _ = Rt.T
    alpha0 = math.radians(aircraft.alpha_zero_lift_deg)
    alpha_slope = math.radians(aircraft.alpha_1g_deg) - alpha0
    alpha = alpha0 + alpha_slope * nz
    alpha_dot = alpha_slope * nzdot

    # attitude: R_ned_from_body = Rz(chi) Ry(gamma) Rx(mu) Ry(alpha)
    R_nb = _stack_rz(chi) @ _stack_ry(gamma) @ _stack_rx(mu) @ _stack_ry(alpha)
    pitch = -np.arcsin(np.clip(R_nb[:, 2, 0], -1.0, 1.0))
    roll = np.arctan2(R_nb[:, 2, 1], R_nb[:, 2, 2])
    heading = np.arctan2(R_nb[:, 1, 0], R_nb[:, 0, 0])

    # body rates: wind-axes rates from (chi, gamma, mu) rates, then turned by alpha
    p_w = mu_dot - chi_dot * np.sin(gamma)
    q_w = gamma_dot * np.cos(mu) + chi_dot * np.cos(gamma) * np.sin(mu)
    r_w = -gamma_dot * np.sin(mu) + chi_dot * np.cos(gamma) * np.cos(mu)
    ca, sa = np.cos(alpha), np.sin(alpha)
    omega_body = np.stack([ca * p_w - sa * r_w, q_w + alpha_dot, sa * p_w + ca * r_w], axis=1)

    # Euler roll rate for the roll-rate limit check: phi' = p + (q sin phi + r cos phi) tan theta
    roll_rate = omega_body[:, 0] + (omega_body[:, 1] * np.sin(roll) + omega_body[:, 2] * np.cos(roll)) * np.tan(pitch)

    v_ned = np.stack([V * np.cos(gamma) * np.cos(chi), V * np.cos(gamma) * np.sin(chi), -V * np.sin(gamma)], axis=1) + W
    return Trajectory(scenario=scenario, rate_hz=rate_hz, t_s=t_s, p_ned_m=S[:, :3].copy(), v_ned_mps=v_ned,
                      roll_rad=roll, pitch_rad=pitch, heading_rad=heading, omega_body_rps=omega_body,
                      gamma_rad=gamma, chi_rad=chi, nz_g=nz, alpha_rad=alpha, roll_rate_rps=roll_rate,
                      bank_cmd_rad=O[:, 0], nz_cmd_g=O[:, 1], wind_ned_mps=W, end_reason=end_reason)


def _stack_rx(a):
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(a), np.ones_like(a)
    return np.stack([np.stack([o, z, z], -1), np.stack([z, c, -s], -1), np.stack([z, s, c], -1)], -2)


def _stack_ry(a):
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(a), np.ones_like(a)
    return np.stack([np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)], -2)


def _stack_rz(a):
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(a), np.ones_like(a)
    return np.stack([np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2)


# --------------------------------------------------------------------------- closed loop: flare and touchdown
@dataclass(frozen=True)
class FlareParams:
    """Flare law and main gear (``visland fly``).

    Flare (an exponential flare, the classic autoland law): below ``flare_height_m`` of main-gear
    height ``h`` the vertical speed order is ``h'_c = -s_td - (h / h_f) (V tan(gs) - s_td)``, so it
    starts at the glide-path sink rate and tends to ``s_td`` on the ground (the height decays with
    the time constant ``tau = h_f / (V tan(gs) - s_td)`` towards ``-s_td tau``, which the gear
    meets at the sink rate ``s_td``). The order is flown as a load factor on the vertical speed
    error, ``nz_c = cos(gamma)/cos(mu) + k_hdot (h'_c - h') / g`` (the glide-path law's flight-path
    loop, 0.3 /s, is too slow for a flare of three seconds). The lateral law stays the localizer's
    (no decrab, no rollout).

    Main gear: ``gear_body_m`` from the centre of gravity in body axes (x forward, z down); the
    aircraft touches down when the gear reaches the runway surface.

    Attributes
    ----------
    flare_height_m : float
        Main-gear height ``h_f`` where the flare starts, metres.
    touchdown_sink_mps : float
        Sink rate ``s_td`` the flare tends to, m/s.
    k_hdot_per_s : float
        Gain of the vertical-speed loop, 1/s.
    gear_body_m : tuple of 3 floats
        Main gear position from the centre of gravity, body axes, metres.
    go_around_gamma_deg : float
        Climb angle of a go-around, degrees.
    """

    flare_height_m: float = 15.0
    touchdown_sink_mps: float = 0.6
    k_hdot_per_s: float = 1.0
    gear_body_m: tuple = (-2.0, 0.0, 3.0)
    go_around_gamma_deg: float = 4.0

    def __post_init__(self):
        for name in ("flare_height_m", "touchdown_sink_mps", "k_hdot_per_s", "go_around_gamma_deg"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"flare {name} must be positive, got {value!r}")
        if len(self.gear_body_m) != 3 or not all(math.isfinite(v) for v in self.gear_body_m):
            raise ValueError(f"flare gear_body_m must be three finite numbers, got {self.gear_body_m!r}")

    def hdot_order_mps(self, gear_height_m: float, ground_speed_mps: float, tan_gs: float) -> float:
        """Vertical speed order (m/s, up positive) at main-gear height ``gear_height_m``."""
        glide_sink = ground_speed_mps * tan_gs
        h = max(gear_height_m, 0.0)
        return -self.touchdown_sink_mps - (h / self.flare_height_m) * max(glide_sink - self.touchdown_sink_mps, 0.0)


@dataclass
class AircraftState:
    """What the aircraft is doing now (truth, SI): the camera sits at the centre of gravity.

    Attributes
    ----------
    t_s : float
        Time, seconds.
    p_runway_m : ndarray, shape (3,)
        Position in the runway frame R, metres.
    v_runway_mps, v_ned_mps : ndarray, shape (3,)
        Ground velocity in R and in NED, m/s.
    roll_rad, pitch_rad, heading_rad : float
        ZYX Euler angles of the body from NED, radians.
    dpsi_rad : float
        Heading minus runway heading, radians.
    omega_body_rps : ndarray, shape (3,)
        Body rates (p, q, r), rad/s.
    gamma_rad, mu_rad : float
        Flight-path angle and bank, radians.
    nz_g : float
        Load factor, g.
    """

    t_s: float
    p_runway_m: np.ndarray
    v_runway_mps: np.ndarray
    v_ned_mps: np.ndarray
    roll_rad: float
    pitch_rad: float
    heading_rad: float
    dpsi_rad: float
    omega_body_rps: np.ndarray
    gamma_rad: float
    mu_rad: float
    nz_g: float

    def frame_states(self) -> FrameStates:
        """This state as a one-frame :class:`FrameStates` (for feature projection and rendering)."""
        return FrameStates(t_s=np.array([self.t_s]), p_runway_m=self.p_runway_m[None, :].copy(),
                           v_ned_mps=self.v_ned_mps[None, :].copy(), v_runway_mps=self.v_runway_mps[None, :].copy(),
                           roll_rad=np.array([self.roll_rad]), pitch_rad=np.array([self.pitch_rad]),
                           heading_rad=np.array([self.heading_rad]), dpsi_rad=np.array([self.dpsi_rad]),
                           omega_body_rps=self.omega_body_rps[None, :].copy())


class FlightModel:
    """The aircraft of :func:`simulate_flight`, stepped one 1/rate_hz at a time with orders held
    over the step (a digital autopilot), so a closed loop can choose the orders from estimates.

    ``guidance_orders(p_runway_m, v_runway_mps)`` gives the ILS laws' orders for a perceived
    position and velocity; ``flare_orders(...)`` and ``go_around_orders()`` the flare's and a
    go-around's; ``step(bank_cmd_rad, nz_cmd_g)`` integrates (RK4) and reports a main-gear
    touchdown inside the step (``touchdown``: time, gear position in R, sink rate).

    Parameters
    ----------
    scenario : Scenario
        Initial conditions, runway and wind.
    aircraft : AircraftParams, optional
        Responses and limits (default :class:`AircraftParams`).
    guidance : GuidanceParams, optional
        Gains of the ILS laws.
    flare : FlareParams, optional
        The flare law and main gear.
    rate_hz : float, default 50
        Step rate, Hz.
    """

    def __init__(self, scenario: Scenario, aircraft: AircraftParams | None = None,
                 guidance: GuidanceParams | None = None, flare: FlareParams | None = None, rate_hz: float = 50.0):
        self.scenario = scenario
        self.aircraft = aircraft or AircraftParams()
        self.guidance_params = guidance or GuidanceParams()
        self.flare = flare or FlareParams()
        self.dt = 1.0 / rate_hz
        self.V = scenario.airspeed_mps
        self.guide = _Guidance(self.guidance_params, scenario, self.V)
        self.R_ned_from_rwy = R_ned_from_runway(scenario.runway.heading_rad)
        self.R_rwy_from_ned = self.R_ned_from_rwy.T
        p0_runway = np.array([scenario.runway.aim_distance_m + scenario.dx_m, scenario.dy_m,
                              -scenario.initial_height_m])
        p0 = self.R_ned_from_rwy @ p0_runway
        gamma0 = math.radians(scenario.gamma_deg)
        mu0 = math.radians(scenario.roll_deg)
        self.state = np.array([p0[0], p0[1], p0[2], gamma0, scenario.runway.heading_rad + math.radians(scenario.dpsi_deg),
                               mu0, math.cos(gamma0) / math.cos(mu0), 0.0])
        self.t_s = 0.0
        self.crosswind_t0 = 0.0 if scenario.wind.crosswind_onset_m is None else None
        self.gust_t0 = None
        self.touchdown = None
        self._last_rates = (0.0, 0.0, 0.0, 0.0)
        self._orders = (mu0, self.state[6])

    # ---- kinematics
    def _wind_ned(self, t):
        w = _wind_runway_mps(self.scenario.wind, t, self.crosswind_t0, self.gust_t0)
        return self.R_ned_from_rwy @ np.array(w)

    def _derivative(self, t, s, bank_cmd, nz_cmd):
        a = self.aircraft
        _, _, _, gamma, chi, mu, nz, nzdot = s
        V = self.V
        wn, we, wd = self._wind_ned(t)
        cg = math.cos(gamma)
        vn = V * cg * math.cos(chi) + wn
        ve = V * cg * math.sin(chi) + we
        vd = -V * math.sin(gamma) + wd
        w = a.nz_omega_rad_s
        roll_rate_max = math.radians(a.roll_rate_limit_dps)
        gamma_dot = G_MPS2 / V * (nz * math.cos(mu) - cg)
        chi_dot = G_MPS2 * nz * math.sin(mu) / (V * cg)
        mu_dot = max(-roll_rate_max, min(roll_rate_max, (bank_cmd - mu) / a.roll_time_constant_s))
        nz_ddot = w * w * (nz_cmd - nz) - 2.0 * a.nz_damping * w * nzdot
        return np.array([vn, ve, vd, gamma_dot, chi_dot, mu_dot, nzdot, nz_ddot])

    def _gear_height_m(self, s):
        """Main-gear height above the runway surface (slope included) for state ``s``."""
        p_rwy = self.R_rwy_from_ned @ s[:3]
        R_nb = _R_ned_from_body(s[4], s[3], s[5], self._alpha(s[6]))
        gear_rwy = p_rwy + self.R_rwy_from_ned @ (R_nb @ np.asarray(self.flare.gear_body_m, float))
        surface_z = -gear_rwy[0] * self.scenario.runway.slope_pct / 100.0
        return float(surface_z - gear_rwy[2]), gear_rwy

    def _alpha(self, nz):
        a = self.aircraft
        alpha0 = math.radians(a.alpha_zero_lift_deg)
        return alpha0 + (math.radians(a.alpha_1g_deg) - alpha0) * nz

    def gear_height_m(self) -> float:
        return self._gear_height_m(self.state)[0]

    def current(self) -> AircraftState:
        """The state now, with the attitude, rates and velocities the inertial unit measures."""
        s = self.state
        gamma, chi, mu, nz, nzdot = s[3], s[4], s[5], s[6], s[7]
        alpha = self._alpha(nz)
        R_nb = _R_ned_from_body(chi, gamma, mu, alpha)
        pitch = -math.asin(max(-1.0, min(1.0, R_nb[2, 0])))
        roll = math.atan2(R_nb[2, 1], R_nb[2, 2])
        heading = math.atan2(R_nb[1, 0], R_nb[0, 0])
        d = self._derivative(self.t_s, s, *self._orders)
        gamma_dot, chi_dot, mu_dot = d[3], d[4], d[5]
        a = self.aircraft
        alpha_dot = (math.radians(a.alpha_1g_deg) - math.radians(a.alpha_zero_lift_deg)) * nzdot
        p_w = mu_dot - chi_dot * math.sin(gamma)
        q_w = gamma_dot * math.cos(mu) + chi_dot * math.cos(gamma) * math.sin(mu)
        r_w = -gamma_dot * math.sin(mu) + chi_dot * math.cos(gamma) * math.cos(mu)
        ca, sa = math.cos(alpha), math.sin(alpha)
        omega = np.array([ca * p_w - sa * r_w, q_w + alpha_dot, sa * p_w + ca * r_w])
        v_ned = d[:3]
        dpsi = (heading - self.scenario.runway.heading_rad + math.pi) % (2 * math.pi) - math.pi
        return AircraftState(t_s=self.t_s, p_runway_m=self.R_rwy_from_ned @ s[:3], v_runway_mps=self.R_rwy_from_ned @ v_ned,
                             v_ned_mps=v_ned, roll_rad=roll, pitch_rad=pitch, heading_rad=heading, dpsi_rad=dpsi,
                             omega_body_rps=omega, gamma_rad=gamma, mu_rad=mu, nz_g=nz)

    # ---- orders
    def guidance_orders(self, p_runway_m, v_runway_mps):
        """Bank and load-factor orders of the ILS laws for a perceived position and velocity."""
        self.guide.update_mode(p_runway_m, v_runway_mps)
        return self.guide.orders(p_runway_m, v_runway_mps, self.state[3], self.state[5])

    def _vertical_orders(self, hdot_cmd):
        g = self.guide
        gamma, mu = self.state[3], self.state[5]
        gamma_cmd = math.asin(max(-0.5, min(0.5, hdot_cmd / self.V)))
        gamma_cmd = max(g.gamma_min, min(g.gamma_max, gamma_cmd))
        nz_cmd = math.cos(gamma) / math.cos(mu) + self.V / G_MPS2 * g.p.k_gamma_per_s * (gamma_cmd - gamma)
        return max(g.p.nz_min_g, min(g.p.nz_max_g, nz_cmd))

    def flare_orders(self, bank_cmd_rad, gear_height_m, ground_speed_mps, hdot_mps):
        """The flare: the localizer's bank order kept, the load factor from the flare law
        (``hdot_mps`` the vertical speed, up positive, as the inertial unit measures it)."""
        g = self.guide
        hdot_cmd = self.flare.hdot_order_mps(gear_height_m, ground_speed_mps, g.tan_gs)
        gamma, mu = self.state[3], self.state[5]
        nz_cmd = math.cos(gamma) / math.cos(mu) + self.flare.k_hdot_per_s * (hdot_cmd - hdot_mps) / G_MPS2
        return bank_cmd_rad, max(g.p.nz_min_g, min(g.p.nz_max_g, nz_cmd))

    def go_around_orders(self):
        """Wings level, climb at ``go_around_gamma_deg``."""
        return 0.0, self._vertical_orders(self.V * math.sin(math.radians(self.flare.go_around_gamma_deg)))

    # ---- integration
    def step(self, bank_cmd_rad: float, nz_cmd_g: float) -> None:
        """Integrate one step with the orders held; sets ``touchdown`` when the gear meets the runway."""
        s, t, dt = self.state, self.t_s, self.dt
        x_r = (self.R_rwy_from_ned @ s[:3])[0]
        wind = self.scenario.wind
        if wind.crosswind_onset_m is not None and self.crosswind_t0 is None and -x_r <= wind.crosswind_onset_m:
            self.crosswind_t0 = t
        if wind.gust and self.gust_t0 is None and -x_r <= wind.gust_onset_m:
            self.gust_t0 = t
        self._orders = (bank_cmd_rad, nz_cmd_g)
        h_before, _ = self._gear_height_m(s)
        f = self._derivative
        k1 = f(t, s, bank_cmd_rad, nz_cmd_g)
        k2 = f(t + dt / 2, s + dt / 2 * k1, bank_cmd_rad, nz_cmd_g)
        k3 = f(t + dt / 2, s + dt / 2 * k2, bank_cmd_rad, nz_cmd_g)
        k4 = f(t + dt, s + dt * k3, bank_cmd_rad, nz_cmd_g)
        new = s + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        h_after, gear_after = self._gear_height_m(new)
        if self.touchdown is None and h_after <= 0.0 < h_before:
            fraction = h_before / (h_before - h_after)
            _, gear_before = self._gear_height_m(s)
            gear = gear_before + fraction * (gear_after - gear_before)
            self.touchdown = {"t_s": t + fraction * dt, "gear_runway_m": gear,
                              "sink_rate_mps": (h_before - h_after) / dt}
        self.state = new
        self.t_s = t + dt


def _R_ned_from_body(chi, gamma, mu, alpha) -> np.ndarray:
    """``Rz(chi) Ry(gamma) Rx(mu) Ry(alpha)`` for one sample (module docstring)."""
    a = np.array([chi, gamma, mu, alpha], dtype=float)
    return (_stack_rz(a[0:1]) @ _stack_ry(a[1:2]) @ _stack_rx(a[2:3]) @ _stack_ry(a[3:4]))[0]
