"""Issue 12, the config path: bad input of any kind is one InputError naming the key.

Three layers: hand-written hostile cases, the corpus ``tests/corpus/config/*.toml`` (each
file says in its first lines ``# expect: TEXT`` and ``# study: NAME``), and hypothesis
properties over random TOML documents and random ``--set`` strings built from the valid
keys (they resolve, or raise InputError, never anything else).
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
import tomli_w
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from evomotion.core.checks import ALLOW_INF
from evomotion.errors import InputError
from evomotion.run import limits
from evomotion.run.ask_tell import make_optimizer
from evomotion.run.config import (
    RunSection,
    config_from_dict,
    config_from_run_dir,
    config_to_toml,
    load_toml,
    resolve_config,
    study_algorithms,
    study_of_run,
)
from evomotion.run.limits import check_memory
from evomotion.studies import STUDIES, get_study

CORPUS = Path(__file__).resolve().parents[1] / "corpus" / "config"
F = get_study("functions")
CHEAP = ("functions", "quadruped-plan", "arm-ik", "grid-path")  # problems built in ms


def resolve_and_build(study, file=None, overrides=()):
    """Everything a run does with its input before the first generation (cheap studies)."""
    cfg = resolve_config(study, file, list(overrides))
    if study.name in CHEAP:
        problem = study.make_problem(cfg.problem)
        check_memory(study, cfg, problem)
        own = study.algorithms.get(cfg.algorithm.name)
        own[1](problem, cfg) if own else make_optimizer(problem, cfg.algorithm)
    return cfg


def one_line(e: pytest.ExceptionInfo) -> str:
    msg = str(e.value)
    assert "\n" not in msg and msg.strip() == msg and msg
    return msg


# --- files -------------------------------------------------------------------------------

def test_non_utf8_names_file_line_byte_and_column(tmp_path):
    f = tmp_path / "c.toml"
    f.write_bytes(b"[run]\nseed = 1\ngenerations = \xff3\n")
    with pytest.raises(InputError) as e:
        resolve_config(F, f)
    assert one_line(e) == f"{f}:3: expected UTF-8 text (byte 0xff at column 15)"


def test_non_utf8_column_counts_characters_not_bytes(tmp_path):
    f = tmp_path / "c.toml"
    f.write_bytes('[problem]\nname = "é'.encode() + b"\xc3(" + b'"\n')
    with pytest.raises(InputError, match=r"c\.toml:2: expected UTF-8 text \(byte 0xc3 at "
                                         r"column 10\)"):
        resolve_config(F, f)


def test_bom_is_accepted(tmp_path):
    f = tmp_path / "c.toml"
    f.write_bytes(b"\xef\xbb\xbf[run]\nseed = 4\n")
    assert resolve_config(F, f).run.seed == 4


def test_directory_is_one_line(tmp_path):
    with pytest.raises(InputError) as e:
        resolve_config(F, tmp_path)
    assert one_line(e) == f"{tmp_path}: expected a TOML file, got a directory"


def test_missing_file_is_one_line(tmp_path):
    with pytest.raises(InputError, match="expected an existing TOML file"):
        resolve_config(F, tmp_path / "nope.toml")


def test_fifo_and_device_are_refused_without_blocking(tmp_path):
    fifo = tmp_path / "c.toml"
    os.mkfifo(fifo)
    with pytest.raises(InputError, match="expected a regular TOML file, got a FIFO"):
        resolve_config(F, fifo)
    with pytest.raises(InputError, match="got a character device"):
        resolve_config(F, "/dev/zero")


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads any file")
def test_unreadable_file_is_one_line(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text("[run]\n")
    f.chmod(0)
    with pytest.raises(InputError, match="expected a readable TOML file"):
        resolve_config(F, f)


def test_oversized_file(tmp_path):
    f = tmp_path / "c.toml"
    f.write_bytes(b"# " + b"x" * (1 << 21) + b"\n")
    with pytest.raises(InputError, match="at most"):
        load_toml(f)


def test_deeply_nested_toml(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text("[run]\nseed = " + "[" * 20000 + "]" * 20000 + "\n")
    with pytest.raises(InputError, match="invalid TOML"):
        resolve_config(F, f)


def test_run_folder_with_a_non_string_study(tmp_path):
    (tmp_path / "config.toml").write_text("study = [1]\n")
    with pytest.raises(InputError, match="'study' key"):
        config_from_run_dir(tmp_path)
    with pytest.raises(InputError, match="'study' key"):
        study_of_run(tmp_path)


def test_study_of_run_names_the_study_or_none(tmp_path):
    assert study_of_run(tmp_path) is None and study_of_run(tmp_path / "missing") is None
    (tmp_path / "f").write_text("x")
    assert study_of_run(tmp_path / "f") is None
    (tmp_path / "config.toml").write_text('study = "humanoid-walk"\n')
    assert study_of_run(tmp_path) == "humanoid-walk"


# --- the cases of the issue ----------------------------------------------------------------

@pytest.mark.parametrize("item,key", [
    ("problem.half_width=nan", "problem.half_width: expected a finite number, got nan"),
    ("problem.half_width=inf", "problem.half_width: expected a finite number, got inf"),
    ("problem.half_width=-inf", "problem.half_width"),
    ("problem.half_width=1e300", "problem.half_width: expected a value in [0.0, 1e+100]"),
    ("problem.dim=1000000000", "problem.dim: expected at most 1000000 genes"),
    ("problem.dim=1e9", "problem.dim: expected int"),
    ("algorithm.pop_size=1e9", "algorithm.pop_size: expected int"),
    ("algorithm.mutation_params={bogus=1}",
     "algorithm.mutation_params: unknown parameter 'bogus' for mutation 'gaussian'; "
     "valid: sigma, gene_rate"),
    ("algorithm.mutation_params={sigma=nan}", "algorithm.mutation_params.sigma: expected a "
                                              "finite number, got nan"),
    ("algorithm.mutation_params.sigma=-1", "algorithm.mutation_params.sigma: expected > 0.0"),
    ("run.wall_seconds=nan", "run.wall_seconds: expected a finite number, got nan"),
    ("run.wall_seconds=inf", "run.wall_seconds"),
    ("run.stagnation_eps=nan", "run.stagnation_eps"),
    ("run.target=nan", "run.target"),
])
def test_issue_cases(item, key):
    with pytest.raises(InputError) as e:
        resolve_config(F, None, [item])
    assert key in one_line(e)


def test_population_too_big_for_memory():
    with pytest.raises(InputError) as e:
        resolve_config(F, None, ["algorithm.pop_size=1000000000"])
    msg = one_line(e)
    assert re.fullmatch(r"algorithm\.pop_size=1000000000 x 30 genes: the population needs "
                        r"about [\d.]+ TB, more than the [\d.]+ [kMGT]?B available", msg), msg


def test_memory_check_against_a_small_machine(monkeypatch):
    cfg = resolve_config(F, None, ["algorithm.pop_size=1000", "problem.dim=1000"])
    monkeypatch.setattr(limits, "available_bytes", lambda: 20_100_000)
    with pytest.raises(InputError, match=r"algorithm\.pop_size=1000 x 1000 genes: the "
                                         r"population needs about 128\.0 MB, more than the "
                                         r"20\.1 MB available"):
        check_memory(F, cfg, F.make_problem(cfg.problem))
    monkeypatch.setattr(limits, "available_bytes", lambda: None)  # unknown: no refusal
    check_memory(F, cfg)


def test_memory_check_uses_the_problem_genome():
    cfg = resolve_config(get_study("grid-path"), None, ["algorithm.pop_size=100"])
    problem = get_study("grid-path").make_problem(cfg.problem)
    terms = limits.memory_terms(cfg, problem)
    assert terms[0][0] == 100 * problem.genome.dim * 8 * limits.POPULATION_FACTOR


def test_quadruped_max_seconds():
    q = get_study("quadruped-plan")
    with pytest.raises(InputError, match="algorithm.max_seconds: expected a finite number"):
        resolve_config(q, None, ["algorithm.max_seconds=nan"])
    with pytest.raises(InputError, match="algorithm.max_seconds"):
        resolve_config(q, None, ["algorithm.max_seconds=-inf"])
    # the old place (problem.max_seconds, before issue 32) names the new one
    with pytest.raises(InputError, match="algorithm.max_seconds: expected a finite number"):
        resolve_config(q, None, ["problem.max_seconds=nan"])
    # inf is the documented "no time limit", and survives config.toml
    cfg = resolve_config(q, None, ["algorithm.max_seconds=inf"])
    assert cfg.algorithm.max_seconds == math.inf
    assert config_from_dict(q, tomllib.loads(config_to_toml(cfg))) == cfg


def test_quadruped_old_and_new_key_together_is_one_line(tmp_path):
    q = get_study("quadruped-plan")
    with pytest.raises(InputError) as e:
        resolve_config(q, None, ["problem.method=astar", "algorithm.method=astar"])
    assert one_line(e) == ("problem.method and algorithm.method: the same setting under its "
                           "old and its new name; give only algorithm.method")
    f = tmp_path / "c.toml"
    f.write_text("[problem]\nweight = 2.0\n[algorithm]\nweight = 2.0\n")
    with pytest.raises(InputError, match="^problem.weight and algorithm.weight: "):
        resolve_config(q, f)
    # the old key in one source, the new in another: the later source wins, as for any key
    f.write_text("[problem]\nweight = 2.0\n")
    assert resolve_config(q, f, ["algorithm.weight=4.0"]).algorithm.weight == 4.0


def test_every_inf_field_documents_its_meaning():
    classes = [RunSection]
    for name in STUDIES:
        s = get_study(name)
        classes += [s.problem_config, *study_algorithms(s).values()]
    for cls in classes:
        for f in dataclasses.fields(cls):
            if ALLOW_INF in f.metadata:
                assert isinstance(f.metadata[ALLOW_INF], str) and f.metadata[ALLOW_INF]


# --- more hostile input ----------------------------------------------------------------------

@pytest.mark.parametrize("study,item,key", [
    ("functions", "algorithm.pop_size=-5", "pop_size must be >= 2"),
    ("functions", "algorithm.pop_size=true", "algorithm.pop_size: expected int, got bool"),
    ("functions", "algorithm.pop_size=\"many\"", "algorithm.pop_size: expected int"),
    ("functions", "algorithm.pop_size=[1, 2]", "algorithm.pop_size: expected int"),
    ("functions", "algorithm.pop_size=100000000000000000000000", "algorithm.pop_size: expected "
                                                                "an integer of at most 64 bits"),
    ("functions", "problem.dim=-1", "problem.dim must be >= 1"),
    ("functions", "problem.dim=0", "problem.dim must be >= 1"),
    ("functions", "problem.name=", "unknown function ''"),
    ("functions", "problem.name=[1]", "problem.name: expected str"),
    ("functions", "algorithm.name=", "unknown algorithm ''"),
    ("functions", "algorithm.mutation=", "unknown mutation ''"),
    ("functions", "algorithm.mutation_params=3", "algorithm.mutation_params: expected dict"),
    ("functions", "algorithm.crossover_params=[1]", "algorithm.crossover_params: expected dict"),
    ("functions", "algorithm.crossover_params.alpha=-1", "algorithm.crossover_params.alpha"),
    ("functions", "algorithm.crossover_params.alpha=\"wide\"",
     "algorithm.crossover_params.alpha: expected a number, got str"),
    ("functions", "algorithm.crossover_params.alpha=true", "algorithm.crossover_params.alpha"),
    ("functions", "algorithm.crossover_params.alpha=none", "algorithm.crossover_params.alpha"),
    ("functions", "algorithm.selection_params.k=0", "algorithm.selection_params.k"),
    ("functions", "algorithm.selection_params.k=100000", "algorithm.selection_params.k: "
                                                         "expected a value in [1, 100]"),
    ("functions", "algorithm.selection_params.k=2.0", "algorithm.selection_params.k: expected "
                                                      "an integer"),
    ("functions", "algorithm.selection_params={size=3}", "unknown parameter 'size' for "
                                                         "selection 'tournament'; valid: k"),
    ("functions", "algorithm.mutation_params.gene_rate=2", "algorithm.mutation_params.gene_rate"),
    ("functions", "algorithm.crossover_rate=nan", "algorithm.crossover_rate"),
    ("functions", "algorithm.crossover_rate=1.5", "algorithm.crossover_rate must be in [0, 1]"),
    ("functions", "algorithm.elitism=inf", "algorithm.elitism"),
    ("functions", "run.seed=-1", "run.seed: expected >= 0"),
    ("functions", "run.generations=-3", "run.generations must be >= 0"),
    ("functions", "run.workers=100000", "run.workers: expected a value in [0, 4096]"),
    ("functions", "run.chunks_per_worker=0", "run.chunks_per_worker must be >= 1"),
    ("functions", "run.evaluator=", "unknown evaluator ''"),
    ("functions", "run.address=\"a\\u0000b\"", "run.address: expected text without NUL"),
    ("functions", "run.seed.x=1", "run.seed: expected int, got dict"),
    ("functions", "algorithm.name=cga", None),  # valid: resolves
    ("functions", "algorithm.name=cmaes", None),
    ("quadruped-plan", "algorithm.weight=nan", "algorithm.weight"),
    ("quadruped-plan", "problem.weight=nan", "algorithm.weight"),  # the old place (issue 32)
    ("quadruped-plan", "problem.gif_max_frames=0", "problem.gif_max_frames"),
    ("quadruped-plan", "problem.goal_x=1e300", "problem.goal_x"),
    ("quadruped-plan", "problem.sector_half_width=3", "sector_half_width"),
    ("quadruped-plan", "algorithm.batch_expansions=-1", "algorithm.batch_expansions"),
    ("arm-ik", "problem.tolerance=0", "problem.tolerance"),
    ("arm-ik", "problem.cell_size=-1", "problem.cell_size"),
    ("arm-ik", "problem.gif_frames=0", "problem.gif_frames"),
    ("arm-ik", "problem.scenario=", "problem.scenario: expected a non-empty string"),
    ("arm-ik", "algorithm.tournament_k=0", "algorithm.tournament_k"),
    ("arm-ik", "algorithm.mutation_rate=2", "algorithm.mutation_rate"),
    ("arm-ik", "algorithm.pop_size=7", "algorithm.pop_size: expected an even number"),
    ("grid-path", "problem.map=random:x:0.1:1", "problem.map: expected 'random:SIZE"),
    ("grid-path", "problem.map=random:100000:0.1:1", "problem.map SIZE"),
    ("grid-path", "problem.map=random:20:1.5:1", "problem.map DENSITY"),
    ("grid-path", "problem.start=1,2,3", "problem.start must be 'x,y'"),
    ("grid-path", "problem.rule=diagonal", "problem.rule"),
    ("grid-path", "problem.m=0", "problem.m"),
    ("grid-path", "problem.n_parts=1000000", "problem.n_parts"),
    ("grid-path", "problem.repair_radius=0", "problem.repair_radius"),
    ("grid-path", "algorithm.rows=7", "not a multiple of rows 7"),
    ("humanoid-step", "problem.intervals=1000000000", "problem.intervals"),
    ("humanoid-step", "problem.motion_s=nan", "problem.motion_s"),
    ("humanoid-step", "problem.motion_s=1e9", "problem.motion_s: expected a value in (0.0, "
                                              "60.0], got 1000000000.0"),
    ("humanoid-step", "problem.threads=100000", "problem.threads"),
    ("humanoid-step", "problem.encoding=wavelet", "problem.encoding"),
    ("biped-kick", "problem.roll_after_s=1e12", "problem.roll_after_s: expected a value in "
                                                "[0.0, 60.0], got 1000000000000.0"),
    ("biped-kick", "algorithm.pop_size=100000000", "the simulated trajectories need about"),
    ("biped-kick", "problem.rolling_m=-1", "problem.rolling_m"),
    ("biped-kick", "problem.nthread=-1", "problem.nthread"),
    ("biped-kick", "problem.fall_tilt_rad=inf", "problem.fall_tilt_rad"),
    ("biped-kick", "algorithm.levy_beta=3", "algorithm.levy_beta: Lévy index beta must be in "
                                           "(0, 2]"),
    ("biped-kick", "algorithm.chaos_mu=2.5", "algorithm.chaos_mu: Tent map slope"),
    ("biped-kick", "algorithm.max_restarts=-1", "algorithm.max_restarts"),
])
def test_hostile_overrides(study, item, key):
    s = get_study(study)
    if key is None:
        resolve_and_build(s, None, [item])
        return
    with pytest.raises(InputError) as e:
        resolve_and_build(s, None, [item])
    assert key in one_line(e)


def test_perturb_k_larger_than_the_genome_is_refused_when_the_optimizer_is_built():
    with pytest.raises(InputError, match=r"algorithm\.mutation_params\.k: expected a value in "
                                         r"\[1, 4\], got 9"):
        resolve_and_build(F, None, ["problem.dim=4", "algorithm.mutation=perturb_k",
                                    "algorithm.mutation_params={k=9}"])


def test_grid_path_m_too_small_is_refused_when_the_problem_is_built():
    with pytest.raises(InputError, match="problem.m: 1e-06 divides"):
        resolve_and_build(get_study("grid-path"), None, ["problem.m=1e-6"])


def test_switching_the_mutation_drops_the_defaults_parameters():
    # functions' defaults give gaussian sigma = 0.001; they belong to gaussian
    cfg = resolve_config(F, None, ["algorithm.mutation=uniform_reset"])
    assert cfg.algorithm.mutation_params == {}
    cfg = resolve_config(F, None, ["algorithm.mutation=gaussian"])
    assert cfg.algorithm.mutation_params == {"sigma": 0.001}
    cfg = resolve_config(F, None, ["algorithm.mutation=perturb_k",
                                   "algorithm.mutation_params.k=2"])
    assert cfg.algorithm.mutation_params == {"k": 2}


def test_a_config_built_in_python_is_held_to_the_same_rules():
    from evomotion.core.ga import GAConfig
    from evomotion.studies.functions.problem import FunctionsConfig

    with pytest.raises(InputError, match="problem.half_width"):
        FunctionsConfig(half_width=math.nan).validate()
    with pytest.raises(InputError, match="algorithm.mutation_params"):
        GAConfig(mutation_params={"sigma": math.inf}).validate()


def test_cli_prints_one_line_and_exits_2(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b"[problem]\nhalf_width = 1\xfe\n")
    for args in (["--config", str(bad)], ["--set", "problem.half_width=nan"]):
        r = subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "functions", *args],
                           capture_output=True, text=True, cwd=tmp_path, timeout=300)
        lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
        assert r.returncode == 2 and len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
        assert lines[0].startswith("error: ")
        assert ("bad.toml:2: expected UTF-8 text (byte 0xfe" in lines[0]
                or "problem.half_width: expected a finite number, got nan" in lines[0])


# --- the corpus --------------------------------------------------------------------------

CORPUS_FILES = sorted(CORPUS.glob("*.toml"))


def test_corpus_is_large_enough():
    assert len(CORPUS_FILES) >= 30
    assert all(re.fullmatch(r"\d{3}-[a-z0-9-]+\.toml", f.name) for f in CORPUS_FILES)


@pytest.mark.parametrize("path", CORPUS_FILES, ids=lambda p: p.stem)
def test_corpus_file_is_an_input_error(path):
    head = path.read_bytes()[:400]
    expect = re.search(rb"^# expect: (.*)$", head, re.M)[1].decode()
    study = re.search(rb"^# study: (\S+)$", head, re.M)[1].decode()
    with pytest.raises(InputError) as e:
        resolve_and_build(get_study(study), path)
    assert expect in one_line(e)


# --- properties ----------------------------------------------------------------------------

#: generated examples per property: 300 + 300 (``EVOMOTION_CONFIG_EXAMPLES=N`` for a longer hunt)
EXAMPLES_SET = EXAMPLES_TOML = int(os.environ.get("EVOMOTION_CONFIG_EXAMPLES", "300"))

_scalars = st.one_of(
    st.integers(-3, 300), st.integers(), st.booleans(),
    st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([0.0, -0.0, 0.5, 1.0, 2.0]),
    st.text(max_size=12), st.sampled_from(["", "none", "ga", "cga", "cmaes", "gaussian",
                                           "perturb_k", "rank", "one_point", "ackley"]))
_values = st.recursive(_scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=3), st.dictionaries(st.sampled_from(
        ["k", "sigma", "alpha", "gene_rate", "pressure", "delta", "bogus"]), inner, max_size=3)),
    max_leaves=6)


def _keys(study) -> dict[tuple[str, str], object]:
    """Every settable key of ``study`` (section, dotted name) -> a plausible value (the
    dataclass default where there is one)."""
    keys: dict[tuple[str, str], object] = {}
    classes = [("run", RunSection)] + [("algorithm", c) for c in study_algorithms(study).values()]
    for sec, cls in classes + [("problem", study.problem_config)]:
        for f in dataclasses.fields(cls):
            default = f.default if f.default is not dataclasses.MISSING else {}
            keys.setdefault((sec, f.name), default)
    for op in ("crossover", "mutation", "selection"):
        for p, v in (("k", 2), ("sigma", 0.1), ("alpha", 0.5), ("gene_rate", 0.2),
                     ("pressure", 1.5), ("delta", 0.1), ("swap_prob", 0.5), ("bogus", 1)):
            keys[("algorithm", f"{op}_params.{p}")] = v
    return dict(sorted(keys.items()))


def _plausible(default):
    """Values near ``default``: itself, small changes, other operator and algorithm names."""
    if isinstance(default, bool):
        return st.booleans()
    if isinstance(default, int | float):
        return st.sampled_from([default, default * 2, default + 1, default - 1, 0, -default,
                                type(default)(1), type(default)(3)])
    if isinstance(default, str):
        return st.sampled_from([default, "ga", "cga", "cmaes", "gaussian", "uniform_reset",
                                "perturb_k", "rank", "roulette", "one_point", "sbx", "ackley",
                                "Margolus", "synchronous", "astar", "random:12:0.2:3"])
    return _values


def _value_for(data, study_keys, sec, key):
    return data.draw(st.one_of(_plausible(study_keys[(sec, key)]), _values),
                     label=f"{sec}.{key}")


FUNCTION_KEYS = _keys(F)


def _outcome(fn) -> None:
    try:
        fn()
    except InputError as e:
        assert "\n" not in str(e) and str(e)


def _toml_text(v) -> str:
    """A value as ``--set`` text: its TOML form (tables and odd values as they come)."""
    if isinstance(v, str):
        return v
    try:
        return tomli_w.dumps({"v": v})[4:].strip()
    except (TypeError, ValueError):
        return repr(v)


@settings(max_examples=EXAMPLES_SET, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_random_set_strings_resolve_or_raise_input_error(data):
    """Random ``--set`` items on the functions study; what resolves is also built (problem,
    memory check, optimizer), as a run would before its first generation."""
    keys = data.draw(st.lists(st.sampled_from(list(FUNCTION_KEYS)), max_size=4), label="keys")
    overrides = []
    for sec, key in keys:
        text = data.draw(st.one_of(_plausible(FUNCTION_KEYS[(sec, key)]).map(_toml_text),
                                   _values.map(_toml_text), st.text(max_size=20)),
                         label=f"{sec}.{key}")
        overrides.append(f"{sec}.{key}={text}")
    _outcome(lambda: resolve_and_build(F, None, overrides))


@settings(max_examples=EXAMPLES_TOML, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(st.sampled_from(sorted(STUDIES)), st.data())
def test_random_toml_documents_resolve_or_raise_input_error(tmp_path, name, data):
    """Random TOML documents of every study's keys (resolved, not built)."""
    study = get_study(name)
    study_keys = _keys(study)
    keys = data.draw(st.lists(st.sampled_from(list(study_keys)), max_size=5), label="keys")
    doc: dict = {}
    for sec, key in keys:
        node = doc.setdefault(sec, {})
        *path, leaf = key.split(".")
        for p in path:
            node = node.setdefault(p, {}) if isinstance(node.get(p, {}), dict) else {}
        node[leaf] = _value_for(data, study_keys, sec, key)
    f = tmp_path / "random.toml"
    try:
        f.write_text(tomli_w.dumps(doc))
    except (TypeError, ValueError):  # tomli_w cannot write it (e.g. NUL in a key)
        return
    _outcome(lambda: resolve_config(study, f))
