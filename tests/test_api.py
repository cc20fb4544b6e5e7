"""The public Python API: ``evomotion.__all__``, ``evomotion.run`` / ``load_run``, ask/tell
without a run folder, the README's Python example and ``examples/`` (each executed), the
import cost of ``import evomotion`` and the API reference build."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import evomotion as em
from evomotion.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
ENV = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), *sys.path]))


class Sphere:
    genome = em.GenomeSpec(lower=np.full(4, -2.0), upper=np.full(4, 2.0))
    sense = "min"
    metric_names = ("norm",)

    def evaluate(self, x):
        return em.Evaluation((x**2).sum(axis=1), {"norm": np.linalg.norm(x, axis=1)})


def test_every_public_name_resolves_and_is_documented():
    assert "run" in em.__all__ and "load_run" in em.__all__
    for name in em.__all__:
        obj = getattr(em, name)
        if name != "__version__" and callable(obj) or isinstance(obj, type):
            assert (obj.__doc__ or "").strip(), name
    assert callable(em.run) and em.run is sys.modules["evomotion.run"]
    assert (ROOT / "src" / "evomotion" / "py.typed").is_file()
    with pytest.raises(AttributeError):
        em.nope  # noqa: B018


def test_import_evomotion_is_light():
    code = "import sys, evomotion; print(sorted(m for m in ('numpy', 'mujoco', 'matplotlib', " \
           "'scipy', 'rich', 'typer') if m in sys.modules))"
    r = subprocess.run([sys.executable, "-c", code], env=ENV, capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 0 and r.stdout.strip() == "[]", (r.stdout, r.stderr)


def test_run_own_problem_gives_the_cli_run_folder_and_resumes(tmp_path):
    cfg = {"algorithm": {"name": "ga", "pop_size": 20},
           "run": {"generations": 6, "seed": 2, "checkpoint_every": 2}}
    whole = em.run(Sphere(), cfg, tmp_path / "whole")
    assert whole.generation == 6 and whole.best_fitness < 1.0
    for f in ("config.toml", "stats.csv", "best.json", "log.txt", "plots/fitness.png"):
        assert (tmp_path / "whole" / f).is_file(), f
    part = em.run(Sphere(), {**cfg, "run": {**cfg["run"], "generations": 3}}, tmp_path / "part")
    assert part.generation == 3
    more = em.run(Sphere(), {"run": {"generations": 6}}, tmp_path / "part", resume=True)
    assert more.best_fitness == whole.best_fitness
    a, b = em.load_run(tmp_path / "whole"), em.load_run(tmp_path / "part")
    for col in ("generation", "evaluations", "best", "mean", "best_so_far"):
        np.testing.assert_array_equal(a.stats[col], b.stats[col])
    assert a.study == "Sphere" and a.best_fitness == whole.best_fitness
    assert a.best_genome.shape == (4,) and "plots/fitness.png" in a.artifacts
    assert a.config["algorithm"]["pop_size"] == 20 and a.log[0].startswith("run Sphere")
    assert json.loads((tmp_path / "whole" / "best.json").read_text())["study"] == "Sphere"


def test_run_a_study_by_name_without_a_folder():
    res = em.run("functions", {"problem": {"name": "sphere", "dim": 5},
                               "run": {"generations": 5}})
    assert res.generation == 5 and np.isfinite(res.best_fitness)


@pytest.mark.parametrize("call,msg", [
    (lambda: em.run(Sphere(), {"run": {"bogus": 1}}), "unknown key 'run.bogus'"),
    (lambda: em.run(Sphere(), {"algorithm": {"name": "nope"}}), "unknown algorithm 'nope'"),
    (lambda: em.run(Sphere(), {"run": 3}), "'run' must be a table"),
    (lambda: em.run(Sphere(), [1]), "config must be a dict"),
    (lambda: em.run(object()), "the problem has no 'genome'"),
    (lambda: em.run(Sphere(), resume=True), "resume=True needs the out_dir"),
    (lambda: em.run("no-such-study"), "unknown study 'no-such-study'"),
    (lambda: em.load_run("/nonexistent/run"), "not a run folder"),
    (lambda: em.make_optimizer("ga", Sphere.genome, popsize=3), "unknown setting 'popsize'"),
    (lambda: em.make_optimizer("map_elites", Sphere.genome), "needs measures="),
])
def test_bad_api_input_is_one_input_error(call, msg):
    with pytest.raises(InputError, match=re.escape(msg)):
        call()


@pytest.mark.parametrize("name", sorted(em.ALGORITHMS))
def test_ask_tell_without_a_run_folder(name):
    measures = em.MeasureSpec(("x0", "x1"), np.array([-2.0, -2.0]), np.array([2.0, 2.0]),
                              (5, 5))
    opt = em.make_optimizer(name, Sphere.genome, measures=measures)
    rng = np.random.default_rng(0)
    state = opt.init(rng)
    first = None
    for _ in range(15):
        x, state = opt.ask(state, rng)
        ev = Sphere().evaluate(x)
        kw = {"measures": x[:, :2]} if opt.needs_measures else {}
        state = opt.tell(state, x, ev.fitness, rng, **kw)
        first = opt.best(state)[1] if first is None else first
    assert opt.best(state)[1] <= first and np.isfinite(opt.best(state)[1])


def _python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S)


def test_readme_python_example_runs(tmp_path, monkeypatch, capsys):
    block = _python_blocks()[0]
    assert len(block.strip().splitlines()) <= 30
    assert "cmaes" in block and "resume=True" in block and "load_run" in block
    monkeypatch.chdir(tmp_path)
    exec(compile(block, "README.md", "exec"), {"__name__": "readme"})
    out = capsys.readouterr().out.split()
    assert float(out[0]) < 1e-3  # CMA-ES solved Rosenbrock in 400 generations
    assert out[1] == "401" and (tmp_path / "runs" / "rosenbrock" / "best.json").is_file()


@pytest.mark.parametrize("example", ["own_objective", "own_mujoco_model", "resume",
                                     "ray_cluster"])
def test_example_runs(example, tmp_path):
    if example == "ray_cluster":
        pytest.importorskip("ray")
    r = subprocess.run([sys.executable, str(ROOT / "examples" / f"{example}.py"),
                        str(tmp_path / "out")], env=ENV, capture_output=True, text=True,
                       timeout=600, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "Traceback" not in r.stderr and r.stdout.strip()
    if example == "own_mujoco_model":
        forward = json.loads((tmp_path / "out" / "best.json").read_text())["metrics"]
        assert 0.2 < forward["forward_m"] < 3.0  # it crawls, without flying away
    if example == "resume":
        assert "stats identical: True" in r.stdout


def test_api_reference_builds(tmp_path):
    pytest.importorskip("pdoc")
    r = subprocess.run([sys.executable, str(ROOT / "scripts" / "api_docs.py"),
                        str(tmp_path / "api")], env=ENV, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr
    index = (tmp_path / "api" / "evomotion.html").read_text()
    for name in ("load_run", "CMAES", "GenomeSpec", "make_optimizer"):
        assert name in index
    assert (tmp_path / "api" / "evomotion" / "sim" / "warp_rollout.html").is_file()
