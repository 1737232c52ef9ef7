"""Scoring of the approach robustness study (benchmarks/detection_robustness_approach.py) on
measurements made from the exact labels with known errors planted: no rendering, no detector.

The dataset files are a real simulated approach's (labels.csv, truth.csv, camera.json,
runway.json); measurements.csv is its labels with, in chosen frames, the runway not found, a
near corner moved (6, 8) px (10 px: a gross error), a near corner moved (0.3, 0.4) px (0.5 px:
not gross), the near corners withheld, dpsi 0.2 deg off, and a far corner moved (-7.2, 9.6) px
(12 px: a gross error too, the near corners exact)."""
import importlib.util
import json
import math
from pathlib import Path

import numpy as np
import pytest

from visland.contracts import MEASUREMENT_COLUMNS, read_labels, read_truth, write_csv
from visland.datasets.stream import write_dataset_files
from visland.estimation.metrics import FT_TO_M
from visland.simulate import run_simulation

from tests.helpers.short_approach import short_job

_SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "detection_robustness_approach.py"


@pytest.fixture(scope="module")
def study():
    spec = importlib.util.spec_from_file_location("detection_robustness_approach", _SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    """A dataset (metadata of a 256 px, 2 Hz short approach) and a run whose measurements are
    its labels with planted errors; returns (dataset, run, planted frames)."""
    root = tmp_path_factory.mktemp("approach_scoring")
    job = short_job(256, 2.0)
    dataset, run = root / "dataset", root / "run"
    write_dataset_files(run_simulation(job.scenario, job.options), dataset)
    labels = read_labels(dataset / "labels.csv")
    n = len(labels["t_s"])
    columns = {c: np.array(labels[c], dtype=float) for c in MEASUREMENT_COLUMNS[:-4]}
    columns["source"] = ["detection"] * n
    columns["found"] = np.ones(n)
    columns["reason"] = [""] * n
    columns["confidence"] = np.ones(n)
    lost, gross, small, withheld, dpsi, far = 1, 2, 3, 4, 5, 6
    for name in columns:
        if name not in ("t_s", "frame", "source", "found", "reason", "confidence") and not name.endswith("_visible"):
            columns[name][lost] = math.nan
    columns["found"][lost] = 0.0
    columns["reason"][lost] = "no runway"
    columns["near_left_u_px"][gross] += 6.0
    columns["near_left_v_px"][gross] += 8.0
    columns["near_right_u_px"][small] += 0.3
    columns["near_right_v_px"][small] -= 0.4
    for name in ("near_left_u_px", "near_left_v_px", "near_right_u_px", "near_right_v_px"):
        columns[name][withheld] = math.nan
    columns["near_left_visible"][withheld] = columns["near_right_visible"][withheld] = 0.0   # not reported
    columns["dpsi_deg"][dpsi] += 0.2
    columns["far_right_u_px"][far] -= 7.2
    columns["far_right_v_px"][far] += 9.6
    run.mkdir()
    write_csv(run / "measurements.csv", columns, MEASUREMENT_COLUMNS)
    return dataset, run, {"lost": lost, "gross": gross, "small": small, "withheld": withheld, "dpsi": dpsi,
                          "far": far}


def test_frame_rows_find_the_planted_errors(study, folders):
    dataset, run, planted = folders
    labels = read_labels(dataset / "labels.csv")
    truth = read_truth(dataset / "truth.csv")
    rows = study.frame_rows("c", run, dataset)
    assert len(rows) == len(labels["t_s"])
    for i in planted.values():           # the planted frames are far out, both near corners in the image
        assert rows[i]["above_100ft"] == 1 and labels["near_left_visible"][i] == labels["near_right_visible"][i] == 1
    lost = rows[planted["lost"]]
    assert lost["found"] == 0 and math.isnan(lost["near_px"]) and lost["gross"] == 0 and lost["reason"] == "no runway"
    assert rows[planted["gross"]]["near_px"] == pytest.approx(10.0, abs=1e-6) and rows[planted["gross"]]["gross"] == 1
    assert rows[planted["small"]]["near_px"] == pytest.approx(0.5, abs=1e-6) and rows[planted["small"]]["gross"] == 0
    w = rows[planted["withheld"]]
    assert w["found"] == 1 and w["corners_withheld"] == 2 and math.isnan(w["near_px"]) and w["gross"] == 0
    assert rows[planted["dpsi"]]["dpsi_err_deg"] == pytest.approx(0.2, abs=1e-9)
    far = rows[planted["far"]]
    assert labels["far_right_visible"][planted["far"]] == 1
    assert far["far_px"] == pytest.approx(12.0, abs=1e-6) and far["near_px"] < 1e-6 and far["gross"] == 1
    assert rows[planted["gross"]]["far_px"] < 1e-6
    others = [r for i, r in enumerate(rows) if i not in planted.values() and r["found"]]
    assert others and all(r["near_px"] < 1e-6 or math.isnan(r["near_px"]) for r in others)
    assert all(r["edge_px"] < 1e-3 for r in others if math.isfinite(r["edge_px"]))
    assert all(abs(r["dpsi_err_deg"]) < 1e-9 for r in others)
    # distance to the threshold and height from truth.csv and runway.json
    aim = json.loads((dataset / "runway.json").read_text())["aim_distance_m"]
    assert rows[0]["distance_m"] == pytest.approx(-(truth["dx_m"][0] + aim))
    assert [r["above_100ft"] for r in rows] == [int(h >= 100 * FT_TO_M) for h in truth["dh_m"]]


def test_summary_and_verdict_count_the_planted_errors(study, folders):
    dataset, run, _ = folders
    rows = study.frame_rows("c", run, dataset)
    above = [r for r in rows if r["above_100ft"]]
    s = study.summarise_rows(rows)["all"]
    assert s["frames"] == len(above)
    assert s["found_rate"] == pytest.approx(round((len(above) - 1) / len(above), 4))
    assert s["gross"] == 2 and s["withheld"] == 2
    assert s["near_corner_px"]["max"] == pytest.approx(10.0, abs=1e-3)
    (run / "metrics.json").write_text(json.dumps({"observers": {"ccpi-hg-2p": {"err_100ft_m": -0.25},
                                                                "ekf-2l": {"err_100ft_m": None}}}))
    dh = study.dh_at_100ft(run)
    assert dh == {"ccpi-hg-2p": -0.25, "ekf-2l": None}
    verdict = study.passes(study.summarise_rows(rows), dh)
    assert not verdict["found"] and not verdict["no_gross"] and not verdict["max"] and not verdict["all"]
    assert verdict["median"] and verdict["dh_100ft"]
    # without the planted errors every criterion holds
    clean = [dict(r, found=1, gross=0, near_px=0.0, dpsi_err_deg=0.0, corners_withheld=0) for r in rows]
    assert study.passes(study.summarise_rows(clean), dh)["all"]
    assert not study.passes(study.summarise_rows(clean), {"ccpi-hg-2p": 0.31})["all"]
    table = study.markdown_table({"c": {"summary": study.summarise_rows(rows), "dh_100ft_m": dh, "pass": verdict}})
    assert len(table) == 3 and table[2].startswith("| c |") and "-0.25 / no estimate" in table[2]
    # an observer that diverged has no 100 ft error; the table says when it diverged
    (run / "metrics.json").write_text(json.dumps({"observers": {
        "ccpi-hg-2p": {"err_100ft_m": None, "diverged_t_s": 48.1}, "ekf-2l": {"err_100ft_m": 1.5, "diverged_t_s": None}}}))
    dh, lost = study.dh_at_100ft(run), study.diverged(run)
    assert dh == {"ccpi-hg-2p": None, "ekf-2l": 1.5} and lost == {"ccpi-hg-2p": 48.1}
    assert not study.passes(study.summarise_rows(clean), dh)["dh_100ft"]
    table = study.markdown_table({"c": {"summary": study.summarise_rows(clean), "dh_100ft_m": dh, "diverged": lost,
                                        "pass": study.passes(study.summarise_rows(clean), dh)}})
    assert "| diverged at 48 s / 1.50 | no |" in table[2]


def test_define_makes_a_condition_of_ones_own_and_names_what_is_wrong(study):
    assert study.defined_condition('{"jpeg_quality": 50}') == ((3000.0, 45.0), {"jpeg_quality": 50}, None)
    runway, scene, lens = study.defined_condition(
        '{"surface": "concrete", "runway_m": [1800, 30], "distortion": [-0.1, 0, 0, 0, 0]}')
    assert runway == (1800.0, 30.0) and scene == {"surface": "concrete"} and lens == (-0.1, 0, 0, 0, 0)
    for text, words in (('{"jpeg_quality": ', "not JSON"), ("[50]", "JSON object"),
                        ('{"runway_m": [3000]}', "runway_m"), ('{"distortion": [0.1]}', "distortion"),
                        ('{"no_such_field": 1}', "no_such_field"), ('{"jpeg_quality": 500}', "jpeg_quality")):
        with pytest.raises(ValueError, match=words):
            study.defined_condition(text)


def test_any_variety_draw_names_a_condition(study):
    """'variety N' is the scene drawn from seed N: draws other than the study's own 1-3 are scenes
    the detector was not tuned on (held out)."""
    from visland.render.variety import draw_variety
    try:
        assert study.add_varieties(["variety 7", "baseline 3000x45", "variety seven", "variety 1"]) == ["variety 7"]
        runway, scene, lens = study.condition_setup("variety 7")
        drawn = draw_variety(7)
        assert (runway.length_m, runway.width_m) == (drawn.runway_length_m, drawn.runway_width_m)
        assert scene == drawn.scene and lens is None
        assert scene != study.condition_setup("variety 1")[1]
    finally:
        study.CONDITIONS.pop("variety 7", None)
