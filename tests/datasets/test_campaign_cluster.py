"""``visland campaign --scheduler`` on a local Dask cluster against the same campaign run here.

Independent truth: the serial campaign (every scenario rendered, measured and estimated in this
process). On the cluster every scenario is one task, all submitted before any result is written,
each working in a folder of its worker's own; the client writes what comes back. The runs must be
the serial ones byte for byte, the recorded paths the campaign's own, and an unreachable scheduler
one sentence.
"""
import json

import pytest

from visland.cli import main
from visland.datasets.campaign import CampaignOptions, run_campaign

SCENARIO = 'name = "{name}"\ndx_m = -1500.0\ndy_m = {dy}\ndgs_m = 0.0\ndpsi_deg = 0.0\ngamma_deg = -3.0\n'
SOURCES = ("detection", "tracking")


def _options(tmp_path, **kwargs):
    names = []
    for name, dy in (("left", -20.0), ("right", 30.0)):
        path = tmp_path / f"{name}.toml"
        path.write_text(SCENARIO.format(name=name, dy=dy))
        names.append(str(path))
    base = dict(scenarios=tuple(names), size=256, fps=1.0, sources=SOURCES, observers=("ccpi-hg-2p",))
    return CampaignOptions(**{**base, **kwargs})


def _same_runs(serial, other, scenarios=("left", "right")):
    for name in scenarios:
        for source in SOURCES:
            run = f"{name}-{source}"
            for file in ("measurements.csv", "estimates.csv", "metrics.json", "camera.json", "telemetry.csv"):
                assert (other / "runs" / run / file).read_bytes() == (serial / "runs" / run / file).read_bytes(), \
                    f"{run}/{file}"
            info = json.loads((other / "runs" / run / "run.json").read_text())
            assert info["input"] == str(other / "datasets" / name)         # the campaign's path, not the worker's
            assert info["n_found"] == json.loads((serial / "runs" / run / "run.json").read_text())["n_found"] > 0
            assert (other / "runs" / run / "report.html").exists()


@pytest.mark.slow
def test_scenarios_run_side_by_side_on_the_cluster_and_equal_the_serial_campaign(tmp_path):
    from distributed import LocalCluster
    serial = tmp_path / "serial"
    run_campaign(_options(tmp_path, prune_frames=True), serial, echo=lambda line: None)
    lines = []
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        pruned = tmp_path / "cluster-pruned"
        run_campaign(_options(tmp_path, prune_frames=True, scheduler=cluster.scheduler_address), pruned,
                     echo=lines.append)
        kept = tmp_path / "cluster-kept"
        left = _options(tmp_path).scenarios[:1]
        run_campaign(_options(tmp_path, scenarios=left, scheduler=cluster.scheduler_address), kept,
                     echo=lambda line: None)
    submitted = [k for k, line in enumerate(lines) if "in memory" in line and cluster.scheduler_address in line]
    returned = [k for k, line in enumerate(lines) if "back from the cluster" in line]
    assert len(submitted) == len(returned) == 2 and max(submitted) < min(returned)     # both out before any back
    _same_runs(serial, pruned)
    _same_runs(serial, kept, scenarios=("left",))
    for name in ("left", "right"):
        assert not (pruned / "datasets" / name / "frames").exists()
        assert (pruned / "datasets" / name / "labels.csv").read_bytes() == \
            (serial / "datasets" / name / "labels.csv").read_bytes()
    manifest = json.loads((kept / "datasets" / "left" / "manifest.json").read_text())       # a complete dataset
    frames = sorted((kept / "datasets" / "left" / "frames").iterdir())
    assert manifest["kind"] == "dataset" and len(frames) == len(manifest["frames"]) > 10
    assert json.loads((pruned / "compare" / "compare.json").read_text()) == \
        json.loads((serial / "compare" / "compare.json").read_text())


def test_an_unreachable_scheduler_is_one_sentence(tmp_path, capsys, monkeypatch):
    import visland.datasets.cluster as cluster
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT_S", 1)
    scenario = tmp_path / "s.toml"
    scenario.write_text(SCENARIO.format(name="s", dy=0.0))
    assert main(["campaign", "--scenarios", str(scenario), "--size", "128", "--fps", "1", "--sources", "detection",
                 "--scheduler", "tcp://127.0.0.1:9", "--out", str(tmp_path / "camp")]) == 2
    err = capsys.readouterr().err.strip()
    assert "--scheduler: cannot reach the Dask scheduler at tcp://127.0.0.1:9" in err and "\n" not in err
