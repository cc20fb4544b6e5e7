"""run.loggers: TensorBoard event files and the rerun recording read back with the packages'
own formats and compared to stats.csv; errors; results unchanged by loggers."""

from __future__ import annotations

import json
import struct
import sys
from pathlib import Path

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.run.config import config_from_dict, config_from_run_dir, resolve_config
from evomotion.run.runner import run_study
from evomotion.run.stats import read_stats

sys.path.insert(0, str(Path(__file__).parent))
from toy_study import STUDY  # noqa: E402

BOTH = 'run.loggers=["tensorboard", "rerun"]'
TB_COLUMNS = {"fitness/best": "best", "fitness/mean": "mean", "fitness/median": "median",
              "fitness/best_so_far": "best_so_far", "run/evaluations": "evaluations",
              "run/evals_per_s": "evals_per_s", "run/diversity": "diversity",
              "run/failed": "failed"}
DETERMINISTIC = ("generation", "evaluations", "best", "mean", "median", "min", "max", "std",
                 "best_so_far", "diversity", "failed")


def read_events(folder: Path) -> dict[str, list[tuple[int, float]]]:
    """``tag -> [(step, value)]`` of the TensorBoard event files in ``folder``, read record by
    record with tensorboardX's protobuf classes, in file order, applying purge events as
    TensorBoard does (a session START at step s drops the earlier events of step >= s)."""
    from tensorboardX.proto import event_pb2

    out: dict[str, list[tuple[int, float]]] = {}
    files = sorted(folder.glob("events.out.tfevents.*"))
    assert files, f"no event file in {folder}"
    for path in files:
        data, i = path.read_bytes(), 0
        while i < len(data):
            (n,) = struct.unpack("<Q", data[i:i + 8])
            ev = event_pb2.Event.FromString(data[i + 12:i + 12 + n])
            i += 12 + n + 4  # length, its CRC, the record, its CRC
            if ev.HasField("session_log") and ev.session_log.status == ev.session_log.START:
                for tag, items in out.items():
                    out[tag] = [(s, v) for s, v in items if s < ev.step]
            for v in ev.summary.value:
                out.setdefault(v.tag, []).append((ev.step, v.simple_value))
    return out


def check_events(events: dict, stats: dict) -> None:
    assert set(events) == set(TB_COLUMNS)  # the toy study has no extra columns
    gens = stats["generation"].astype(int)
    for tag, col in TB_COLUMNS.items():
        keep = np.isfinite(stats[col])  # non-finite values are left out
        steps = [s for s, _ in events[tag]]
        assert steps == list(gens[keep]), tag
        np.testing.assert_array_equal([v for _, v in events[tag]],
                                      stats[col][keep].astype(np.float32), err_msg=tag)


def rrd_entities(path: Path) -> dict[str, list]:
    """``entity path -> [record batch as dict]`` of a .rrd, read with rerun's own reader."""
    chunk = pytest.importorskip("rerun.chunk")
    if not hasattr(chunk, "RrdReader"):
        pytest.skip("this rerun-sdk has no .rrd reader")
    out: dict[str, list] = {}
    for c in chunk.RrdReader(path).stream().to_chunks():
        out.setdefault(c.entity_path, []).append(c.to_record_batch().to_pydict())
    return out


def check_series(path: Path, stats: dict) -> dict:
    ents = rrd_entities(path)
    for name in ("best", "mean", "best_so_far"):
        (batch,) = ents[f"/fitness/{name}"]
        assert batch["generation"] == list(stats["generation"].astype(int))
        assert batch["evaluations"] == list(stats["evaluations"].astype(int))
        np.testing.assert_array_equal([v[0] for v in batch["Scalars:scalars"]], stats[name])
    return ents


def test_toy_run_writes_tensorboard_scalars_and_rrd(tmp_path):
    cfg = resolve_config(STUDY, None, ["run.generations=6", BOTH])
    assert cfg.run.loggers == ("tensorboard", "rerun")
    run_study(STUDY, cfg, tmp_path, quiet=True)
    stats = read_stats(tmp_path / "stats.csv")
    check_events(read_events(tmp_path / "tensorboard"), stats)
    if (events := accumulated(tmp_path / "tensorboard")) is not None:
        check_events(events, stats)
    assert (tmp_path / "best.rrd").stat().st_size > 0
    ents = check_series(tmp_path / "best.rrd", stats)
    assert not any(e.startswith("/robot") for e in ents)  # no best.motion: no robot
    _, raw = config_from_run_dir(tmp_path)  # config.toml keeps the loggers
    assert config_from_dict(STUDY, raw).run.loggers == ("tensorboard", "rerun")


def accumulated(folder: Path) -> dict[str, list[tuple[int, float]]] | None:
    """The same, read by TensorBoard's own EventAccumulator (None: tensorboard not installed)."""
    try:
        from tensorboard.backend.event_processing.event_accumulator import EventAccumulator
    except ImportError:
        return None
    ea = EventAccumulator(str(folder))
    ea.Reload()
    return {t: [(e.step, e.value) for e in ea.Scalars(t)] for t in ea.Tags()["scalars"]}


def test_resumed_run_shows_each_generation_once(tmp_path, monkeypatch):
    from evomotion.run import evaluators

    cfg = resolve_config(STUDY, None, ["run.generations=20", "run.checkpoint_every=4", BOTH])
    calls = {"n": 0}
    orig = evaluators.SerialEvaluator.__call__

    def interrupting(self, genomes):
        calls["n"] += 1
        if calls["n"] == 11:  # mid-run, between checkpoints: generations 9, 10 are replayed
            raise KeyboardInterrupt
        return orig(self, genomes)

    monkeypatch.setattr(evaluators.SerialEvaluator, "__call__", interrupting)
    assert run_study(STUDY, cfg, tmp_path, quiet=True).stop_reason == "interrupted"
    assert not (tmp_path / "best.rrd").exists()  # written when the run ends
    monkeypatch.setattr(evaluators.SerialEvaluator, "__call__", orig)
    assert run_study(STUDY, cfg, tmp_path, quiet=True, resume=True).stop_reason == "generations"
    assert len(list((tmp_path / "tensorboard").glob("events.*"))) == 2
    stats = read_stats(tmp_path / "stats.csv")
    check_events(read_events(tmp_path / "tensorboard"), stats)
    if (events := accumulated(tmp_path / "tensorboard")) is not None:
        check_events(events, stats)  # TensorBoard itself drops the purged steps
    check_series(tmp_path / "best.rrd", stats)


@pytest.mark.slow
def test_humanoid_step_rrd_has_the_best_motion(tmp_path):
    from evomotion.studies import get_study

    s = get_study("humanoid-step")
    cfg = resolve_config(s, None, [*s.smoke, "run.generations=1", 'run.loggers=["rerun"]'])
    run_study(s, cfg, tmp_path, quiet=True)
    assert (tmp_path / "best.motion").exists()
    ents = check_series(tmp_path / "best.rrd", read_stats(tmp_path / "stats.csv"))
    frames = int(round((cfg.problem.motion_s + cfg.problem.hold_s) * 50))  # 50 Hz
    for body in ("torso", "Head", "LFoot", "RTibia"):
        (batch,) = ents[f"/robot/bodies/{body}"]
        assert abs(len(batch["sim_time"]) - frames) <= 1
        assert len(batch["Transform3D:translation"]) == len(batch["Transform3D:quaternion"]) \
            == len(batch["sim_time"])
        q = np.array([v[0] for v in batch["Transform3D:quaternion"]])
        np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-5)
    torso = np.array([v[0] for v in ents["/robot/bodies/torso"][0]["Transform3D:translation"]])
    assert 0.2 < torso[0, 2] < 0.5  # the NAO's torso starts ~0.33 m up
    assert "/robot/bodies/LFoot/boxes" in ents and "/robot/bodies/LBicep/capsules" in ents
    assert "/robot/torso_path" in ents and "/robot/torso" in ents


def test_unknown_or_repeated_logger_is_one_line(tmp_path):
    with pytest.raises(InputError) as e:
        resolve_config(STUDY, None, ['run.loggers=["wandb"]'])
    assert str(e.value) == "unknown logger 'wandb'; available: rerun, tensorboard"
    with pytest.raises(InputError, match="'rerun' is named twice"):
        resolve_config(STUDY, None, ['run.loggers=["rerun", "rerun"]'])
    with pytest.raises(InputError, match="run.loggers: expected"):
        resolve_config(STUDY, None, ["run.loggers=3"])


@pytest.mark.parametrize(("name", "module", "package"), [
    ("tensorboard", "tensorboardX", "tensorboardX"), ("rerun", "rerun", "rerun-sdk")])
def test_missing_package_is_one_line_before_any_file(tmp_path, monkeypatch, name, module,
                                                     package):
    monkeypatch.setitem(sys.modules, module, None)  # import fails as if not installed
    monkeypatch.delitem(sys.modules, f"evomotion.run.loggers.{name}", raising=False)
    cfg = resolve_config(STUDY, None, [f'run.loggers=["{name}"]'])
    with pytest.raises(InputError) as e:
        run_study(STUDY, cfg, tmp_path / "run", quiet=True)
    assert str(e.value) == (f"run.loggers: {name!r} needs the {package} package: "
                            f"pip install 'evomotion[{name}]'")
    assert not (tmp_path / "run" / "config.toml").exists()  # the folder holds no run


def test_loggers_do_not_change_results(tmp_path):
    plain = resolve_config(STUDY, None, ["run.generations=8"])
    logged = resolve_config(STUDY, None, ["run.generations=8", BOTH])
    run_study(STUDY, plain, tmp_path / "plain", quiet=True)
    run_study(STUDY, logged, tmp_path / "logged", quiet=True)
    s1, s2 = read_stats(tmp_path / "plain" / "stats.csv"), \
        read_stats(tmp_path / "logged" / "stats.csv")
    assert list(s1) == list(s2)
    for col in DETERMINISTIC:
        np.testing.assert_array_equal(s1[col], s2[col], err_msg=col)
    b1, b2 = (json.loads((tmp_path / d / "best.json").read_text()) for d in ("plain", "logged"))
    assert b1 == b2


def test_resume_may_change_the_loggers():
    from evomotion.run.resume import RESUME_KEYS

    assert "run.loggers" in RESUME_KEYS
