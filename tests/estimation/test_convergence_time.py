"""The 5 % convergence time on a constructed error history whose answers are known by construction.

Thesis 5.2.1: within 5 % "de manière prolongée", evaluated down to 100 ft (``conv_time_5pct_s``);
the strict variant holds the band to the last sample (``conv_time_5pct_to_end_s``).
"""
import json
import math

import numpy as np
import pytest

from visland.contracts import ESTIMATE_COLUMNS, TRUTH_COLUMNS, write_csv
from visland.estimation.metrics import convergence_time_s, run_metrics

# Samples every 0.5 s for 18 s; the true height falls 10 m/s from 190 m: 35 m at 15.5 s, 30 m at
# 16.0 s, so the first sample at or below 100 ft (30.48 m) is t = 16.0 s: the thesis's window ends there.
T_S = np.arange(0.0, 18.01, 0.5)
DH_TRUE_M = 190.0 - 10.0 * T_S
START_T_S = 1.0          # the observer starts at 1 s (no estimate before)


def relative_error_history():
    """dH_hat = dH (1 + r): 30 % off until 3 s, 1 % off after, with excursions (8 %) at 8.0 s and at
    17.0 s (below 100 ft); NaN before the start."""
    r = np.where(T_S < 3.0, 0.30, 0.01)
    r[T_S == 8.0] = 0.08
    r[T_S == 17.0] = -0.10
    r[T_S < START_T_S] = np.nan
    return r


def at(t):
    return int(np.nonzero(np.isclose(T_S, t))[0][0])


def both(r):
    est = DH_TRUE_M * (1.0 + r)
    thesis = convergence_time_s(T_S, DH_TRUE_M, est, start_t_s=START_T_S)
    strict = convergence_time_s(T_S, DH_TRUE_M, est, start_t_s=START_T_S, until_height_m=None)
    return thesis, strict


def test_thesis_window_ends_at_100ft_and_the_strict_one_at_the_last_sample():
    r = relative_error_history()
    thesis, strict = both(r)
    assert thesis == pytest.approx(8.5 - START_T_S)       # last excursion before 100 ft at 8.0 s
    assert strict == pytest.approx(17.5 - START_T_S)      # the one below 100 ft counts too
    m = run_metrics(T_S, DH_TRUE_M, DH_TRUE_M * (1.0 + r), start_t_s=START_T_S)
    assert m["conv_time_5pct_s"] == pytest.approx(7.5) and m["conv_time_5pct_to_end_s"] == pytest.approx(16.5)


def test_an_excursion_on_the_last_sample_leaves_only_the_strict_time_undefined():
    r = relative_error_history()
    r[-1] = 0.06                                           # the case: 16.8 m high, 5.6 % off
    thesis, strict = both(r)
    assert thesis == pytest.approx(7.5)
    assert math.isnan(strict)


def test_the_first_sample_at_or_below_100ft_is_inside_the_window():
    r = relative_error_history()
    r[at(16.0)] = 0.06
    assert math.isnan(both(r)[0])                          # outside at 100 ft: not converged
    r = relative_error_history()
    r[at(15.5)] = 0.06
    assert both(r)[0] == pytest.approx(16.0 - START_T_S)   # back inside at the last sample of the window
    r = relative_error_history()
    r[at(16.5)] = 0.06                                     # past the window: only the strict time moves
    assert both(r) == (pytest.approx(7.5), pytest.approx(16.5))


def test_a_missing_estimate_counts_as_outside_and_time_runs_from_the_start():
    r = relative_error_history()
    r[at(10.0)] = np.nan
    assert both(r)[0] == pytest.approx(10.5 - START_T_S)
    r = relative_error_history()
    r[:at(3.0)] = np.where(np.isnan(r[:at(3.0)]), np.nan, 0.01)     # inside from its first estimate
    r[at(8.0)] = 0.01
    assert both(r)[0] == 0.0
    est = DH_TRUE_M * (1.0 + r)                            # start defaults to the first estimate
    assert convergence_time_s(T_S, DH_TRUE_M, est) == 0.0
    assert math.isnan(convergence_time_s(T_S, DH_TRUE_M, np.full_like(T_S, np.nan)))


def test_a_run_that_stays_above_100ft_is_judged_to_its_end():
    truth = np.full_like(T_S, 100.0)
    est = truth * (1.0 + relative_error_history())
    thesis = convergence_time_s(T_S, truth, est, start_t_s=START_T_S)
    strict = convergence_time_s(T_S, truth, est, start_t_s=START_T_S, until_height_m=None)
    assert thesis == strict == pytest.approx(17.5 - START_T_S)
    with pytest.raises(ValueError, match="until_height_m"):
        convergence_time_s(T_S, truth, est, until_height_m=-1.0)


@pytest.mark.slow
def test_compare_reads_the_start_from_metrics_json_and_shows_the_thesis_time(tmp_path):
    """A hand-made run folder: compare's table holds 7.5 s (thesis) and 16.5 s (strict) for the
    observer that converges before 100 ft, and '-' for the strict time of one whose last sample is off."""
    from visland.datasets.compare import compare_runs
    run = tmp_path / "run"
    run.mkdir()
    n = T_S.size
    zeros = np.zeros(n)
    write_csv(run / "truth.csv", {"t_s": T_S, "dx_m": -1000.0 + 70.0 * T_S, "dy_m": zeros, "dh_m": DH_TRUE_M,
                                  "roll_deg": zeros, "pitch_deg": zeros, "dpsi_deg": zeros}, TRUTH_COLUMNS)
    late = relative_error_history()
    late[-1] = 0.06
    columns = {c: [] for c in ESTIMATE_COLUMNS}
    for name, r in (("ccpi-hg-2p", relative_error_history()), ("kf-2p", late)):
        dh = DH_TRUE_M * (1.0 + r)
        for k in range(n):
            for c, v in zip(ESTIMATE_COLUMNS, (name, T_S[k], -1000.0 + 70.0 * T_S[k], 0.0, dh[k], 45.0, 0.0, 1.0)):
                columns[c].append(v)
    write_csv(run / "estimates.csv", columns, ESTIMATE_COLUMNS)
    (run / "run.json").write_text(json.dumps({"source": "ideal", "scenario": "thesis-1"}))
    # the observers started half a sample before their first estimate, as the runner may record
    (run / "metrics.json").write_text(json.dumps({"observers": {"ccpi-hg-2p": {"start_t_s": 0.75},
                                                                "kf-2p": {"start_t_s": 0.75}}}))
    summary = compare_runs([run], tmp_path / "cmp", echo=lambda text: None)
    dh = summary["ideal"]["dH"]
    assert dh["ccpi-hg-2p"]["conv_time_5pct_s"] == pytest.approx(8.5 - 0.75)
    assert dh["ccpi-hg-2p"]["conv_time_5pct_to_end_s"] == pytest.approx(17.5 - 0.75)
    assert dh["kf-2p"]["conv_time_5pct_s"] == pytest.approx(8.5 - 0.75)
    assert math.isnan(dh["kf-2p"]["conv_time_5pct_to_end_s"])
    table = (tmp_path / "cmp" / "compare.md").read_text()
    assert "| 5 % convergence time (s), thesis-1 | 7.750 | 7.750 |" in table
    assert "| 5 % convergence time to the end of the run (s), thesis-1 | 16.750 | - |" in table
    assert "until the true height first falls to 100 ft" in table


def test_study_notes_name_the_last_excursion_of_cells_more_than_twice_off_the_thesis():
    """Table 5.6's thesis times: ccpi-hg-2p 5.83 s, kf-2p 8.88 s, cccs-2p 5.64 s. A run last outside the
    band at 8.0 s (7.0 s from its start, within 2x) is not noted; one last outside at 15.5 s is, with
    that time, and one converging at 2 s is noted as faster."""
    from types import SimpleNamespace
    from visland.estimation.study import STUDIES, _convergence_notes
    case = SimpleNamespace(dh_true_m=DH_TRUE_M, dx_true_m=-3000.0 + 70.0 * T_S)
    late = relative_error_history()
    late[at(15.5)] = 0.06
    fast = np.where(T_S < START_T_S, np.nan, np.where(T_S < 3.0, 0.30, 0.01))
    runs, results = {}, {}
    for name, r in (("cccs-2p", relative_error_history()), ("ccpi-hg-2p", late), ("kf-2p", fast)):
        dh = DH_TRUE_M * (1.0 + r)
        runs[name] = SimpleNamespace(t_s=T_S, start_t_s=START_T_S, dh_m=dh, observability=np.full(T_S.size, 100.0))
        results[name] = {"conv_time_5pct_s": convergence_time_s(T_S, DH_TRUE_M, dh, start_t_s=START_T_S)}
    assert [results[n]["conv_time_5pct_s"] for n in runs] == [pytest.approx(7.5), pytest.approx(15.0),
                                                              pytest.approx(2.0)]
    lines = []
    notes = _convergence_notes(STUDIES["table-5.6"], results, case, runs, lines.append)
    assert set(notes["observers"]) == {"ccpi-hg-2p", "kf-2p"}
    ccpi = notes["observers"]["ccpi-hg-2p"]
    assert ccpi["kind"] == "slower" and ccpi["last_outside_t_s"] == pytest.approx(15.5 - START_T_S)
    assert ccpi["error_pct"] == pytest.approx(6.0) and ccpi["dh_m"] == pytest.approx(35.0)
    assert notes["observers"]["kf-2p"] == {"kind": "faster"}
    assert len(notes["reasons"]) == 2 and any("Table 5.3 (ideal) row" in r for r in notes["reasons"])
    assert any("ccpi-hg-2p: last outside 5 % at 14.50 s" in line for line in lines)
