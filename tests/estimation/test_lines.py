"""The five two-line observers on simulated approaches (thesis 5.2.1, Table 5.4) and their input policy.

Truth comes from the flight simulator (dH of the flown trajectory) and the exact image lines of
the runway edges (``visland.simulate``, "analyse d'images simulée"). Inputs are built here
from the simulation, as the thesis does: camera velocity, angular velocity and runway axis in
camera axes at 50 Hz, edge lines at the 25 Hz frames.

Two sources of angular velocity are used:

- ``"imu"``: the simulator's recorded body rates (what telemetry.csv holds);
- ``"attitude"``: the mean body rate over each 20 ms interval, from the flown attitudes. The
  simulator holds its guidance orders over each step and records the rate at the start of
  the step, so its recorded roll rate runs up to ~1e-3 rad/s above the rate actually flown
  during the alignment turn; the thesis's ideal inertial unit (hypothesis 2) has no such
  error, so the accuracy figures of Table 5.4 are checked with ``"attitude"``.
"""
from __future__ import annotations

import functools
import json
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from visland.estimation.base import Estimate, ObserverInput
from visland.estimation.lines import (CCCJ2L, CCCJ2LParams, CCPI2L, CCPI2LParams, EKF2L, EKF2LParams, II2L,
                                      II2LParams, LINE_OBSERVERS, OJ2L, OJ2LParams)
from visland.estimation.metrics import convergence_time_s
from visland.features import batch_R_camera_from_runway, batch_R_runway_from_body, observability_lines
from visland.scenarios import get_scenario
from visland.simulate import run_simulation

FT = 0.3048
THESIS_SCENARIOS = [f"thesis-{i}" for i in range(1, 9)]
#: thesis Table 5.4: 5 % convergence time (s) on trajectory 1, ideal measurements
THESIS_CONVERGENCE_S = {"cccj-2l": 2.04, "ii-2l": 6.0, "ccpi-2l": 2.04, "ekf-2l": 3.4, "oj-2l": 5.52}
ALL = sorted(LINE_OBSERVERS)


# --------------------------------------------------------------------------- inputs from the simulation
@functools.lru_cache(maxsize=None)
def _simulation(name: str):
    return run_simulation(get_scenario(name))


def _attitude_rates(tr) -> np.ndarray:
    """Body rates consistent with the flown attitude: mean rate over each interval, averaged at samples."""
    R = batch_R_runway_from_body(tr.roll_rad, tr.pitch_rad, tr.dpsi_rad)
    dt = np.diff(tr.t_s)[:, None]
    mean = Rotation.from_matrix(np.einsum("nji,njk->nik", R[:-1], R[1:])).as_rotvec() / dt
    out = np.empty((len(tr.t_s), 3))
    out[0], out[-1] = mean[0], mean[-1]
    out[1:-1] = 0.5 * (mean[:-1] + mean[1:])
    return out


@functools.lru_cache(maxsize=None)
def make_inputs(name: str, rates: str = "attitude", frame_every: int = 2) -> tuple:
    """``(trajectory, [ObserverInput at 50 Hz])``; edges on the steps whose index is a multiple of ``frame_every``."""
    res = _simulation(name)
    tr = res.trajectory
    cam = res.options.camera
    R_cr = batch_R_camera_from_runway(tr.roll_rad, tr.pitch_rad, tr.dpsi_rad, cam.mount_rpy_rad)
    v_R = tr.v_runway_mps
    v_C = np.einsum("nij,nj->ni", R_cr, v_R)
    omega_B = tr.omega_body_rps if rates == "imu" else _attitude_rates(tr)
    omega_C = omega_B @ cam.R_body_from_camera                     # R_camera_from_body omega_B
    # labels at the 25 Hz frames (exact lines), placed on the 50 Hz steps they fall on
    frame_step = np.rint(res.frames.t_s * tr.rate_hz).astype(int)
    lines = res.features.lines
    measured = {}
    for k, i in enumerate(frame_step):
        if i % frame_every == 0:
            measured[i] = np.array([[lines["left"][0][k], lines["left"][1][k]],
                                    [lines["right"][0][k], lines["right"][1][k]]])
    if frame_every % 2:   # steps between the 25 Hz frames: exact lines from the trajectory
        from visland.features import runway_lines
        L = runway_lines(R_cr, tr.p_runway_m, tr.runway)
        for i in range(0, len(tr.t_s), frame_every):
            measured.setdefault(i, np.array([[L["left"][0][i], L["left"][1][i]],
                                             [L["right"][0][i], L["right"][1][i]]]))
    inputs = [ObserverInput(t_s=float(tr.t_s[i]), v_runway_mps=v_R[i].copy(), v_camera_mps=v_C[i].copy(),
                            omega_camera_rps=omega_C[i].copy(), n_camera=R_cr[i, :, 2].copy(),
                            R_runway_from_camera=R_cr[i].T.copy(), points_yv=None, lines=measured.get(i))
              for i in range(len(tr.t_s))]
    return tr, inputs


def fly(observer, tr, inputs, dh0_factor=1.2) -> list[Estimate]:
    observer.reset(inputs[0], dh0_factor * tr.dh_m[0])
    return [observer.step(inp) for inp in inputs[1:]]


def convergence_time(tr, dh_est, band=0.05) -> float:
    """The thesis's 5 % convergence time (visland.estimation.metrics, thesis 5.2.1) of the estimates
    of steps 1.. from the start at step 0; NaN if it never stays within the band."""
    n = len(dh_est)
    return convergence_time_s(tr.t_s[1:1 + n], tr.dh_m[1:1 + n], dh_est, tolerance=band, start_t_s=tr.t_s[0])


def error_at_height(tr, dh_est, height_ft) -> float:
    i = tr.index_at_height(height_ft * FT)
    return float(tr.dh_m[i] - dh_est[i - 1])


def dh_of(estimates) -> np.ndarray:
    return np.array([e.dh_m for e in estimates])


# --------------------------------------------------------------------------- interface
def test_the_five_spec_observers_are_exposed():
    assert {cls.name for cls in (OJ2L, II2L, CCPI2L, CCCJ2L, EKF2L)} == {"oj-2l", "ii-2l", "ccpi-2l", "cccj-2l",
                                                                        "ekf-2l"}
    assert all(cls.features == "lines" for cls in LINE_OBSERVERS.values())


# --------------------------------------------------------------------------- convergence and accuracy
@pytest.mark.slow
@pytest.mark.parametrize("name", ALL)
def test_converges_on_all_eight_thesis_scenarios(name):
    """Ideal measurements and inertial data: every approach converges within the 5 % band and stays in it."""
    for k, scenario in enumerate(THESIS_SCENARIOS):
        tr, inputs = make_inputs(scenario)
        factor = 1.2 if k % 2 == 0 else 0.8            # the seeds start 20 % off, both ways
        dh = dh_of(fly(LINE_OBSERVERS[name](), tr, inputs, factor))
        assert convergence_time(tr, dh) < 7.0, scenario
        late = tr.t_s[1:] > 10.0
        assert np.max(np.abs(tr.dh_m[1:] - dh)[late] / tr.dh_m[1:][late]) < 1e-3, scenario
        assert abs(error_at_height(tr, dh, 100)) < 0.01, scenario


@pytest.mark.parametrize("name", ALL)
def test_table_5_4_trajectory_1(name):
    """Thesis Table 5.4, trajectory 1: convergence about as fast as the thesis's, millimetre errors at 400/200/100 ft."""
    tr, inputs = make_inputs("thesis-1")
    dh = dh_of(fly(LINE_OBSERVERS[name](), tr, inputs, 1.2))
    assert convergence_time(tr, dh) <= 1.25 * THESIS_CONVERGENCE_S[name]
    for height in (400, 200, 100):
        assert abs(error_at_height(tr, dh, height)) < 0.006, height


@pytest.mark.slow
@pytest.mark.parametrize("name", ALL)
def test_converges_with_the_recorded_body_rates(name):
    """With the simulator's recorded rates the turn biases every observer (module docstring); still within 5 %."""
    for scenario in ("thesis-1", "thesis-4", "thesis-8"):
        tr, inputs = make_inputs(scenario, rates="imu")
        dh = dh_of(fly(LINE_OBSERVERS[name](), tr, inputs, 1.2))
        assert convergence_time(tr, dh) < 7.0, scenario
        assert abs(error_at_height(tr, dh, 100)) < 0.02 * 100 * FT, scenario


@pytest.mark.parametrize("name", ALL)
def test_a_10_hz_camera_is_enough(name):
    tr, inputs = make_inputs("thesis-1", frame_every=5)
    estimates = fly(LINE_OBSERVERS[name](), tr, inputs, 0.8)
    dh = dh_of(estimates)
    assert convergence_time(tr, dh) < 7.0
    assert abs(error_at_height(tr, dh, 100)) < 0.01
    assert sum(e.coasting for e in estimates) == pytest.approx(0.8 * len(estimates), abs=2)


# --------------------------------------------------------------------------- missing measurements
@pytest.mark.parametrize("name", ALL)
def test_coasts_on_the_model_across_missing_frames(name):
    tr, inputs = make_inputs("thesis-1")
    gap = (tr.t_s >= 30.0) & (tr.t_s < 34.0)
    nan_frame = int(np.nonzero(tr.t_s >= 40.0)[0][0] // 2 * 2)
    changed = list(inputs)
    for i in np.nonzero(gap)[0]:
        changed[i] = replace(inputs[i], lines=None)
    changed[nan_frame] = replace(inputs[nan_frame], lines=np.array([[np.nan, 0.1], [0.01, -0.1]]))
    estimates = fly(LINE_OBSERVERS[name](), tr, changed, 1.2)
    dh = dh_of(estimates)
    in_gap = gap[1:]
    assert all(e.coasting for e, g in zip(estimates, in_gap) if g)
    assert {e.reason for e, g in zip(estimates, in_gap) if g} == {"no measurement"}
    assert estimates[nan_frame - 1].coasting and estimates[nan_frame - 1].reason == "non-finite measurement"
    assert all(np.isfinite(e.state).all() and e.dh_m > 0 for e in estimates)
    # the model alone (eta' = v3 eta^2) carries the converged height across the 4 s gap
    assert np.max(np.abs(tr.dh_m[1:] - dh)[in_gap] / tr.dh_m[1:][in_gap]) < 1e-3
    assert abs(error_at_height(tr, dh, 100)) < 0.01


@pytest.mark.parametrize("name", ALL)
def test_never_a_nan_from_the_unobservable_start_with_a_bad_guess(name):
    """Level flight along the runway at t = 0 (thesis Fig. 3.10: Phi = 0), a guess 3x or 1/3 of the truth."""
    tr, inputs = make_inputs("thesis-1")
    first = inputs[0]
    edges = [(first.lines[0, 0], first.lines[0, 1]), (first.lines[1, 0], first.lines[1, 1])]
    assert observability_lines(edges, first.v_camera_mps, first.omega_camera_rps, first.n_camera) < 1e-20
    for factor in (3.0, 1.0 / 3.0):
        estimates = fly(LINE_OBSERVERS[name](), tr, inputs[:1500], factor)
        assert all(np.isfinite(e.state).all() and 0 < e.dh_m < 1e5 and math.isfinite(e.observability)
                   for e in estimates)


def test_observability_index_is_thesis_3_40_on_the_estimated_edges():
    tr, inputs = make_inputs("thesis-1")
    for name in ALL:
        estimates = fly(LINE_OBSERVERS[name](), tr, inputs[:600], 1.2)
        inp, est = inputs[500], estimates[499]
        expected = observability_lines(
            [(inp.lines[0, 0], inp.lines[0, 1]), (inp.lines[1, 0], inp.lines[1, 1])],
            inp.v_camera_mps, inp.omega_camera_rps, inp.n_camera)
        assert est.observability == pytest.approx(float(expected), rel=1e-3), name


@pytest.mark.parametrize("name", ALL)
def test_the_chart_representative_of_a_measured_edge_does_not_matter(name):
    """An edge given as (-rho, theta + pi) (the other side of the SPEC chart) is the same line."""
    tr, inputs = make_inputs("thesis-3")
    flipped = [inp if inp.lines is None else
               replace(inp, lines=np.array([inp.lines[0], [-inp.lines[1, 0], inp.lines[1, 1] + math.pi]]))
               for inp in inputs[:800]]
    a = dh_of(fly(LINE_OBSERVERS[name](), tr, inputs[:800]))
    b = dh_of(fly(LINE_OBSERVERS[name](), tr, flipped))
    np.testing.assert_allclose(a, b, rtol=1e-9)


@pytest.mark.slow
def test_ekf_covariance_stays_symmetric_positive_definite():
    tr, inputs = make_inputs("thesis-7")
    estimates = fly(EKF2L(), tr, inputs, 0.8)
    for e in estimates[::200] + estimates[-1:]:
        P = e.state[5:].reshape(5, 5)
        np.testing.assert_allclose(P, P.T, rtol=1e-9, atol=1e-18)
        assert np.linalg.eigvalsh(0.5 * (P + P.T)).min() > 0


def test_state_layouts():
    tr, inputs = make_inputs("thesis-1")
    sizes = {"ccpi-2l": 5, "oj-2l": 5, "cccj-2l": 9, "ii-2l": 10, "ekf-2l": 30}
    for name, size in sizes.items():
        est = fly(LINE_OBSERVERS[name](), tr, inputs[:300], 1.2)[-1]
        assert est.state.shape == (size,)
        eta = est.state[9] if name == "ii-2l" else est.state[4]
        assert est.dh_m == pytest.approx(1.0 / eta)


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("name", ALL)
def test_programming_errors_raise_value_error(name):
    tr, inputs = make_inputs("thesis-1")
    obs = LINE_OBSERVERS[name]()
    with pytest.raises(ValueError, match="reset"):
        obs.step(inputs[1])
    with pytest.raises(ValueError, match="dh0_m"):
        obs.reset(inputs[0], 0.0)
    with pytest.raises(ValueError, match="dh0_m"):
        obs.reset(inputs[0], float("nan"))
    obs.reset(inputs[0], 250.0)
    with pytest.raises(ValueError, match="lines"):
        obs.step(replace(inputs[2], lines=np.zeros(4)))
    with pytest.raises(ValueError, match="lines"):
        obs.step(replace(inputs[2], lines=np.zeros((3, 2))))
    with pytest.raises(ValueError, match="v_camera_mps"):
        obs.step(replace(inputs[2], v_camera_mps=np.array([np.nan, 0.0, 70.0])))
    with pytest.raises(ValueError, match="omega_camera_rps"):
        obs.step(replace(inputs[2], omega_camera_rps=np.zeros(2)))
    obs.step(inputs[2])
    with pytest.raises(ValueError, match="time must increase"):
        obs.step(inputs[2])
    with pytest.raises(ValueError, match="time must increase"):
        obs.step(inputs[1])


# --------------------------------------------------------------------------- parameters
PARAMS = [(CCPI2LParams, "omega_rps"), (CCCJ2LParams, "epsilon_sq"), (II2LParams, "gain_lambda"),
          (EKF2LParams, "sigma_line"), (OJ2LParams, "gain_alpha")]


@pytest.mark.parametrize("params_type, field", PARAMS)
def test_parameters_validate_and_round_trip(tmp_path, params_type, field):
    with pytest.raises(ValueError, match=field):
        params_type(**{field: -1.0})
    with pytest.raises(ValueError, match=field):
        params_type(**{field: float("nan")})
    tuned = params_type(**{field: getattr(params_type(), field) * 1.5})
    for suffix in (".json", ".toml"):
        path = tmp_path / f"p{suffix}"
        tuned.save(path)
        assert params_type.load(path) == tuned
    data = json.loads((tmp_path / "p.json").read_text())
    data["no_such_gain"] = 1.0
    with pytest.raises(ValueError, match="no_such_gain"):
        params_type.from_dict(data)


def test_every_parameter_is_documented():
    import dataclasses
    for params_type, _ in PARAMS:
        for f in dataclasses.fields(params_type):
            assert f"{f.name} :" in params_type.__doc__ or f"{f.name}," in params_type.__doc__, (params_type, f.name)


def test_parameters_change_the_dynamics():
    """A slower tuning converges later (the gains reach the maths)."""
    tr, inputs = make_inputs("thesis-1")
    slow = {"ccpi-2l": CCPI2LParams(omega_rps=1.0), "cccj-2l": CCCJ2LParams(omega_rps=1.0),
            "ii-2l": II2LParams(gain_lambda=0.005), "oj-2l": OJ2LParams(gain_alpha=0.03),
            "ekf-2l": EKF2LParams(sigma_line=1e-2)}
    for name, params in slow.items():
        fast_t = convergence_time(tr, dh_of(fly(LINE_OBSERVERS[name](), tr, inputs[:1500])))
        slow_t = convergence_time(tr, dh_of(fly(LINE_OBSERVERS[name](params), tr, inputs[:1500])))
        assert slow_t > fast_t + 0.5, name


def test_ii_dynamic_scaling_grows_with_the_filter_error():
    """Thesis 4.27-4.28: a lagging filter raises r (and with it the filter gain), which then relaxes to 1."""
    tr, inputs = make_inputs("thesis-1")
    obs = II2L()
    obs.reset(inputs[0], tr.dh_m[0])
    state = obs._get_state()
    state[0] += 0.05            # filtered theta_left 0.05 rad off the measurement
    state[3] -= 0.02            # filtered rho_right off too
    obs._set_state(state)
    est = obs.step(inputs[1])
    assert est.state[8] > 1.0
    assert abs(est.state[0] - est.state[4]) < 0.05   # pulled towards the measured edge
    for inp in inputs[2:400]:
        est = obs.step(inp)
    assert est.state[8] == pytest.approx(1.0, abs=1e-3)


# --------------------------------------------------------------------------- 5 px corner noise (issue 12)
@functools.lru_cache(maxsize=4)
def _noisy_case(scenario: str):
    """``scenario`` with 5 px of corner noise, seeded as ``visland study lines-5px`` seeds it."""
    from visland.estimation.study import THESIS_SCENARIOS as STUDY_SCENARIOS
    from visland.estimation.study import Condition, simulate_case
    return simulate_case(scenario, Condition("5 px", pixel_noise_px=5.0), seed=STUDY_SCENARIOS.index(scenario))


def _dh_error_at_100ft(name: str, scenario: str, params) -> tuple:
    from visland.estimation.metrics import error_at_height_of
    from visland.estimation.study import _run
    case = _noisy_case(scenario)
    run, _ = _run(name, case, params)
    return error_at_height_of(case.dh_true_m, case.dh_true_m, run.dh_m, 100 * FT), run.diverged


@pytest.mark.slow
@pytest.mark.parametrize("name,scenario,bound_m", [("oj-2l", "thesis-6", 3.0), ("ccpi-2l", "thesis-1", 3.0),
                                                   ("cccj-2l", "thesis-6", 3.0), ("ii-2l", "thesis-3", 5.0)])
def test_no_line_observer_diverges_with_5_px_of_noise(name, scenario, bound_m):
    """Issue 12: with 5 px of corner noise and the 5 px settings of `visland study lines-5px`, each
    line observer keeps an estimate to 100 ft and is within ``bound_m`` there, on a scenario where
    its defaults were cut off as diverged (oj-2l, ccpi-2l, ii-2l on all eight, cccj-2l on thesis-6;
    measured after the fix: -1.02, -0.14, 1.03, -0.62 m)."""
    from visland.estimation.study import SLOW_5PX_PARAMS
    error, diverged = _dh_error_at_100ft(name, scenario, SLOW_5PX_PARAMS[name])
    assert not diverged, diverged
    assert abs(error) < bound_m, error
    _, diverged_with_defaults = _dh_error_at_100ft(name, scenario, None)
    assert diverged_with_defaults


@pytest.mark.slow
def test_oj2l_regressor_at_the_prediction_is_what_keeps_it_with_5_px():
    """oj-2l with the slow 5 px gains but Jankovic's regressor at the measured edges is still thrown
    onto its bound by the noise-regressor correlation (module docstring, "Image noise")."""
    from visland.estimation.study import SLOW_5PX_PARAMS
    params = dict(SLOW_5PX_PARAMS["oj-2l"], regressor_at_measurement=True)
    _, diverged = _dh_error_at_100ft("oj-2l", "thesis-6", params)
    assert diverged


@pytest.mark.slow
def test_ii2l_slow_filter_removes_the_noise_bias_of_the_sampled_increment():
    """The cause of ii-2l's divergence with 5 px: with eta held at the truth on thesis-1, the mean of
    the sampled I&I increment beta(y_meas) - beta(y_model) (4.18, 4.29) over 20-40 s is far above
    its spread with the default filter (y_hat carries the last frame's noise) and within it with the
    5 px settings' slow filter (measured +0.64 and -0.005 per second)."""
    import visland.estimation.lines as lines_module
    from visland.estimation.study import SLOW_5PX_PARAMS
    case = _noisy_case("thesis-1")
    prep = case.prepared
    start = prep.first_step_with("lines")

    def increments(params):
        observer = II2L(params)
        observer.reset(prep.steps[start], float(case.dh_true_m[prep.frame_of_step[start]]))
        calls, out = [], []
        original = lines_module.ii_edge_integral

        def spy(*args):
            calls.append(original(*args))
            return calls[-1]
        lines_module.ii_edge_integral = spy
        try:
            for j in range(start + 1, len(prep.steps)):
                inp, frame = prep.steps[j], prep.frame_of_step[j]
                if frame >= 0:
                    observer._eta = 1.0 / case.dh_true_m[frame]
                calls.clear()
                observer.step(inp)
                if len(calls) == 4 and 20.0 <= inp.t_s < 40.0:
                    out.append(calls[0] - calls[1] + calls[2] - calls[3])
        finally:
            lines_module.ii_edge_integral = original
        out = np.array(out)
        return out.sum() / 20.0, out.std() * math.sqrt(len(out)) / 20.0      # mean per second, its s.e.m.

    mean_default, sem_default = increments(None)
    mean_slow, sem_slow = increments(SLOW_5PX_PARAMS["ii-2l"])
    assert mean_default > 2.0 * sem_default
    assert abs(mean_slow) < 1.0 * sem_slow


@pytest.mark.parametrize("params_type, field", [(OJ2LParams, "regressor_at_measurement"), (II2LParams, "project_state")])
def test_the_5_px_switches_are_booleans_that_round_trip(tmp_path, params_type, field):
    with pytest.raises(ValueError, match=field):
        params_type(**{field: 1.0})
    flipped = params_type(**{field: not getattr(params_type(), field)})
    for suffix in (".json", ".toml"):
        path = tmp_path / f"p{suffix}"
        flipped.save(path)
        assert params_type.load(path) == flipped
