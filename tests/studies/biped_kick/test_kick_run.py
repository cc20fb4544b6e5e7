"""``evomotion run biped-kick`` writes the kick's motion, the aimed variants, the plots, the
per-aim table, named genes and (where offscreen rendering works) the video."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from evomotion.cli import app
from evomotion.sim.motion import read_motion
from evomotion.studies.biped_kick.artifacts import AIMS_DEG
from evomotion.studies.biped_kick.motion import GENES, kick_motion

runner = CliRunner()


@pytest.fixture(scope="module")
def kick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("kick") / "run"
    res = runner.invoke(app, ["run", "biped-kick", "--out", str(out), "--quiet",
                              "--set", "algorithm.pop_size=4", "--set", "run.max_evaluations=8",
                              "--set", "problem.aims_deg=[0.0]", "--set", "problem.nthread=2"])
    assert res.exit_code == 0, res.output
    return out


def test_run_writes_the_kick(kick_run):
    best = json.loads((kick_run / "best.json").read_text())
    assert best["study"] == "biped-kick" and list(best["genes"]) == [g[0] for g in GENES]
    assert "feasible" in best and "violation" in best["metrics"]
    m = read_motion(kick_run / "best.motion")
    assert len(m.joints) == 22
    np.testing.assert_allclose(m.values, kick_motion(np.array(best["genome"])).values,
                               atol=1e-5)
    from evomotion.sim.robots.nao.mirror import mirror_targets

    for a in AIMS_DEG:
        right = read_motion(kick_run / "kicks" / f"aim_{a:+d}.motion")
        # the left foot's kick at +a: the right one's at -a in mirror image
        left = read_motion(kick_run / "kicks" / f"left_aim_{-a:+d}.motion")
        assert left.joints == right.joints and np.array_equal(left.times_ms, right.times_ms)
        np.testing.assert_allclose(left.values, mirror_targets(right.values), atol=1e-12)
        assert not np.allclose(left.values, right.values)
    rows = json.loads((kick_run / "best_kicks.json").read_text())
    assert [r["aim_deg"] for r in rows] == list(AIMS_DEG)
    for name in ("kick_foot.png", "kick_zmp.png", "fitness.png"):
        assert (kick_run / "plots" / name).stat().st_size > 10_000
    log = (kick_run / "log.txt").read_text()
    assert "best kick:" in log
    assert (kick_run / "best.mp4").exists() or "best.mp4 skipped" in log
