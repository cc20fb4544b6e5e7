"""Every optimizer a policy search runs (ARS, OpenAI-ES, PGPE, SNES, CMA-ES) through the gym
study: an interrupted run resumes bit-identically, and the process evaluator gives the serial
evaluator's results (the normaliser and the episode seeds travel in the rows)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from evomotion.run.config import resolve_config  # noqa: E402
from evomotion.run.faults import fault_at  # noqa: E402
from evomotion.run.runner import run_study  # noqa: E402
from evomotion.run.stats import read_stats  # noqa: E402
from evomotion.studies.gym.study import POLICY_OPTIMIZERS, STUDY  # noqa: E402

SETTINGS = ["problem.max_episode_steps=25", "problem.eval_episodes=2", "run.generations=4",
            "run.checkpoint_every=2", "run.seed=5", "algorithm.pop_size=6", "run.evaluator=serial"]
TIMED = {"wall_s", "evals_per_s"}


def _same(a: Path, b: Path) -> None:
    s1, s2 = read_stats(a / "stats.csv"), read_stats(b / "stats.csv")
    assert list(s1) == list(s2)
    for col in s1:
        if col not in TIMED:
            np.testing.assert_array_equal(s1[col], s2[col], err_msg=col)
    assert json.loads((a / "best.json").read_text())["genome"] == \
        json.loads((b / "best.json").read_text())["genome"]
    assert (a / "policy.npz").read_bytes() == (b / "policy.npz").read_bytes()


CASES = [(name, ()) for name in POLICY_OPTIMIZERS] + [("ars", ("algorithm.noise_table=5000",)),
                                                       ("snes", ("algorithm.noise_table=5000",))]


@pytest.mark.parametrize("name, more", CASES)
def test_resume_and_process_evaluator_are_bit_identical(name, more, tmp_path):
    extra = [*(["algorithm.top_directions=0"] if name == "ars" else []), *more]
    cfg = resolve_config(STUDY, None, [*SETTINGS, f"algorithm.name={name}", *extra])
    run_study(STUDY, cfg, tmp_path / "full", quiet=True)
    with fault_at(3, "interrupt"):
        run_study(STUDY, cfg, tmp_path / "cut", quiet=True)
    run_study(STUDY, cfg, tmp_path / "cut", quiet=True, resume=True)
    _same(tmp_path / "full", tmp_path / "cut")
    proc = resolve_config(STUDY, None, [*SETTINGS, f"algorithm.name={name}", *extra,
                                        "run.evaluator=process", "run.workers=2"])
    run_study(STUDY, proc, tmp_path / "proc", quiet=True)
    _same(tmp_path / "full", tmp_path / "proc")


def _arrays(ck: Path) -> tuple[Path, dict[str, np.ndarray]]:
    """The newest checkpoint's npz and its arrays."""
    latest = json.loads((ck / "latest.json").read_text())["checkpoint"]
    npz = ck / latest.replace(".json", ".npz")
    with np.load(npz) as z:
        return npz, {k: z[k] for k in z.files}


def _cut_optimizer_arrays(ck: Path) -> None:
    npz, a = _arrays(ck)
    np.savez(npz, **{k: v[..., :-1] if k.startswith("state.opt.") and v.dtype.kind == "f"
                     and v.ndim and v.shape[-1] > 1 else v for k, v in a.items()})


def _nan_in_optimizer_arrays(ck: Path) -> None:
    npz, a = _arrays(ck)
    for k, v in a.items():
        if k.startswith("state.opt.") and v.dtype.kind == "f" and v.size:
            v.reshape(-1)[0] = np.nan
    np.savez(npz, **a)


def _string_for_a_state_number(ck: Path) -> None:
    latest = ck / json.loads((ck / "latest.json").read_text())["checkpoint"]
    meta = json.loads(latest.read_text())
    meta["state.best_cost"] = "x"
    latest.write_text(json.dumps(meta))


DAMAGE = {"optimizer arrays one short": _cut_optimizer_arrays,
          "NaN in the optimizer's arrays": _nan_in_optimizer_arrays,
          "a string for a state number": _string_for_a_state_number}


@pytest.mark.parametrize("name", POLICY_OPTIMIZERS)
def test_a_damaged_optimizer_state_falls_back_to_the_previous_checkpoint(name, tmp_path):
    """A checkpoint whose optimizer state would break only inside the next generation
    (shapes that do not broadcast, a NaN centre, a string for a number) is refused on resume
    like any damaged checkpoint: a warning, the previous checkpoint, the same results."""
    extra = ["algorithm.top_directions=0"] if name == "ars" else []
    cfg = resolve_config(STUDY, None, [*SETTINGS, f"algorithm.name={name}", *extra])
    run_study(STUDY, cfg, tmp_path / "full", quiet=True)
    with fault_at(3, "interrupt"):
        run_study(STUDY, cfg, tmp_path / "cut", quiet=True)
    for kind, damage in DAMAGE.items():
        d = tmp_path / kind.replace(" ", "-")
        shutil.copytree(tmp_path / "cut", d)
        damage(d / "checkpoints")
        run_study(STUDY, cfg, d, quiet=True, resume=True)
        log = (d / "log.txt").read_text()
        assert "does not fit this run" in log and "skipped" in log, kind
        _same(tmp_path / "full", d)
