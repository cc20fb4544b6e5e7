"""A humanoid-walk run's controller measured beside the walk engine it started from.

``evomotion humanoid-walk compare RUN --worlds 100 --duration 60``:

- **Random commands**: the best centre (``policy.npz``, its frozen normaliser inside) and the
  engine (the fitted tape without feedback: the open-loop walk the search started from) walk
  the **same** ``worlds`` unseen perturbed worlds (seeds from :data:`EVAL_SEED_BASE`, which no
  training episode uses), each ``duration`` seconds of the run's random command schedule with
  one push of up to the run's ``push_max_ns``. Reported: survival (never fallen), mean time up,
  the tracking errors (m/s, rad/s) and the relative error ``Σ|v − v_cmd| / Σ|v_cmd|`` over the
  one-cycle windows while up (velocity and yaw rate apart; ``None``, shown "–", where that
  quantity was never commanded); and the **steady** relative errors:
  the same sums over the windows that begin :data:`SETTLE_S` or more after the command last
  changed (its ramp included), each quantity over the windows where it is commanded
  (``|v_cmd| >= 0.05`` m/s, ``|ω_cmd| >= 0.1`` rad/s): how well a held command is walked,
  without the response to its changes and without drift during the other kinds of command.
- **Top speeds**: each direction commanded alone at the run's range limit (forward ``vx_max``,
  backward ``vx_min``, named ``forward_min`` where ``vx_min > 0``; left/right ``±vy_max``,
  turning ``±yaw_rate_max``) for :data:`SPEED_TEST_S` in the nominal world without a push; the
  walked velocity is the mean over the last half (m/s, deg/s). ``stand``, the zero command,
  gives the walk's **creep**: how fast it drifts while told to step in place (what a go-to-pose
  loop such as ``biped-kick play``'s must stop against).
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import InputError
from evomotion.studies.humanoid_omniwalk.commands import tracking

STUDY_NAME = "humanoid-walk"
EVAL_SEED_BASE = 2**40  # above every training seed (< 2^31)
MAX_WORLDS = 10_000
SPEED_TEST_S = 10.0
BATCH = 20  # worlds per closed-loop call (the recorded states of 60 s are large)
SETTLE_S = 1.0  # a window is steady when it begins this long after the command's last change
STEADY_MIN_V_MPS, STEADY_MIN_W_RPS = 0.05, 0.1  # the commanded quantities of the steady errors
#: a relative error needs more than this summed |command| (m/s or rad/s x windows); else None
MIN_COMMANDED = 1e-6


def steady_windows(cmds: np.ndarray, window: int, settle: int) -> np.ndarray:
    """``[n, C + 1 − window]``: whether each one-cycle window (ending at control step
    ``window .. C``) begins ``settle`` or more control steps after the command of its
    episode (``cmds[n, C, 3]``, ramps included) last changed; the episode's start counts as
    a change."""
    n, C, _ = cmds.shape
    changed = np.zeros((n, C), bool)
    changed[:, 1:] = (cmds[:, 1:] != cmds[:, :-1]).any(axis=2)
    last = np.maximum.accumulate(np.where(changed, np.arange(C)[None], 0), axis=1)
    ends = np.arange(window, C + 1)
    return last[:, ends - 1] <= ends[None] - window - settle


def load_run(path: str | Path, duration_s: float | None = None,
             option: str = "RUN") -> tuple[Any, Any, Path]:
    """(problem, exported policy, run folder) of a humanoid-walk run folder (or its
    ``policy.npz``); the problem's episodes last ``duration_s`` when given."""
    from evomotion.core.policies.export import read_policy_npz
    from evomotion.run.config import config_from_dict, config_from_run_dir, run_of_study
    from evomotion.studies import get_study
    from evomotion.studies.humanoid_omniwalk.problem import OmniWalkProblem

    p = Path(path)
    folder = run_of_study(p.parent if p.name == "policy.npz" else p, STUDY_NAME, option)
    npz = folder / "policy.npz"
    if not npz.is_file():
        raise InputError(f"{option} {path}: no policy.npz yet (the run has not checkpointed "
                         "a policy)")
    _, raw = config_from_run_dir(folder)
    cfg = config_from_dict(get_study(STUDY_NAME), raw).problem
    if duration_s is not None:
        cfg = dataclasses.replace(cfg, duration_s=float(duration_s))
    problem = OmniWalkProblem(cfg)
    policy = read_policy_npz(npz)
    spec = problem.policy
    if (policy.spec.kind, policy.spec.obs_dim, policy.spec.act_dim,
            policy.params.size) != (spec.kind, spec.obs_dim, spec.act_dim, spec.n_params):
        raise InputError(f"{npz}: a {policy.spec.kind} policy of {policy.params.size} "
                         f"parameters; the run's config needs {spec.kind} of {spec.n_params}")
    return problem, policy, folder


def _play(problem, params: np.ndarray, mean: np.ndarray, std: np.ndarray, seeds: np.ndarray,
          commands: np.ndarray | None = None, push_ns: float | None = None) -> dict:
    """Metrics and tracking sums of ``params`` (one controller) in the worlds of ``seeds``."""
    out: dict[str, list] = {}
    for a in range(0, len(seeds), BATCH):
        s = seeds[a:a + BATCH]
        n = len(s)
        cmd = None if commands is None else commands[a:a + BATCH]
        m, res, cmds = problem.play(np.tile(params, (n, 1)), np.tile(mean, (n, 1)),
                                    np.tile(std, (n, 1)), s, push_ns, cmd)
        tr = tracking(res.torso, cmds, problem.ctl.window, problem.ctl.control_dt)
        ev, ew = tr.errors()
        ends = np.arange(problem.ctl.window, cmds.shape[1] + 1)
        up = ends[None] * problem.control_steps <= res.fall_step[:, None]
        cv, cw = np.hypot(tr.cmd[..., 0], tr.cmd[..., 1]), np.abs(tr.cmd[..., 2])
        steady = up & steady_windows(cmds, problem.ctl.window,
                                     int(round(SETTLE_S / problem.ctl.control_dt)))
        sv, sw = steady & (cv >= STEADY_MIN_V_MPS), steady & (cw >= STEADY_MIN_W_RPS)
        m = dict(m, err_v=(ev * up).sum(1), err_w=(ew * up).sum(1),
                 cmd_v=(cv * up).sum(1), cmd_w=(cw * up).sum(1),
                 steady_err_v=(ev * sv).sum(1), steady_cmd_v=(cv * sv).sum(1),
                 steady_err_w=(ew * sw).sum(1), steady_cmd_w=(cw * sw).sum(1),
                 vx=tr.vx, vy=tr.vy, w=tr.yaw_rate)
        for k, v in m.items():
            out.setdefault(k, []).append(v)
    return {k: np.concatenate(v) for k, v in out.items()}


def _relative(err: np.ndarray, cmd: np.ndarray) -> float | None:
    """``Σ err / Σ |cmd|``; None where nothing was commanded (a forward-only run's yaw rate),
    which a ratio to a sum of rounding errors would show as an absurd percentage."""
    total = float(cmd.sum())
    return float(err.sum()) / total if total > MIN_COMMANDED else None


def _summary(m: dict) -> dict[str, Any]:
    return {"survival": float(m["survived"].mean()), "time_up_s": float(m["time_up_s"].mean()),
            "speed_error_mps": float(m["speed_error_mps"].mean()),
            "yaw_rate_error_rps": float(m["yaw_rate_error_rps"].mean()),
            "relative_speed_error": _relative(m["err_v"], m["cmd_v"]),
            "relative_yaw_rate_error": _relative(m["err_w"], m["cmd_w"]),
            "steady_relative_speed_error": _relative(m["steady_err_v"], m["steady_cmd_v"]),
            "steady_relative_yaw_rate_error": _relative(m["steady_err_w"], m["steady_cmd_w"]),
            "power_w": float(m["power_w"].mean()),
            "speed_excess": float(m["speed_excess"].mean())}


def quiet_problem(problem):
    """The top-speed tests' problem: ``problem``'s, nominal world, no push, SPEED_TEST_S."""
    from evomotion.studies.humanoid_omniwalk.problem import OmniWalkProblem

    return OmniWalkProblem(dataclasses.replace(problem.cfg, duration_s=SPEED_TEST_S,
                                               perturb=False, push_min_ns=0.0,
                                               push_max_ns=0.0))


def top_speeds(p, params, mean, std, tests: dict[str, tuple] | None = None
               ) -> dict[str, dict[str, Any]]:
    """Each direction alone at its range limit in ``p`` (a :func:`quiet_problem`; module
    doc), or each command of ``tests`` (name -> (vx, vy, ω)) alone."""
    cfg = p.cfg
    if tests is None:
        slowest = "forward_min" if cfg.vx_min > 0 else "backward"  # forward-only ranges
        tests = {"forward": (cfg.vx_max, 0, 0), slowest: (cfg.vx_min, 0, 0),
                 "left": (0, cfg.vy_max, 0), "right": (0, -cfg.vy_max, 0),
                 "turn_left": (0, 0, cfg.yaw_rate_max),
                 "turn_right": (0, 0, -cfg.yaw_rate_max), "stand": (0, 0, 0)}
    C = math.ceil(p.nstep / p.control_steps)
    t = np.arange(C) * p.ctl.control_dt
    ramp = np.clip(t / cfg.ramp_s, 0.0, 1.0)[None, :, None]
    cmds = np.array(list(tests.values()), float)[:, None, :] * ramp
    m = _play(p, params, mean, std, np.zeros(len(tests), np.int64), cmds)
    half = m["vx"].shape[1] // 2
    out = {}
    for i, name in enumerate(tests):
        out[name] = {"command": [float(v) for v in tests[name]],
                     "vx_mps": float(m["vx"][i, half:].mean()),
                     "vy_mps": float(m["vy"][i, half:].mean()),
                     "yaw_rate_dps": float(np.degrees(m["w"][i, half:].mean())),
                     "fell": bool(m["survived"][i] < 1)}
    return out


def compare(run: str | Path, worlds: int = 100, duration_s: float = 60.0, seed: int = 0,
            capture_gain: float | None = None) -> dict[str, Any]:
    """The run's controller and its engine (module doc); ``capture_gain`` replaces the run's
    (``problem.capture_gain``, :mod:`.capture_step`) for both."""
    from evomotion.core.checks import check_number
    from evomotion.studies.humanoid_omniwalk.problem import OmniWalkProblem

    check_number("--worlds", worlds, lo=1, hi=MAX_WORLDS, integer=True)
    check_number("--duration", duration_s, lo=0.5, hi=600.0)
    check_number("--seed", seed, lo=0, hi=2**20, integer=True)
    if capture_gain is not None:
        check_number("--capture-gain", capture_gain, lo=0.0, hi=3.0)
    problem, policy, folder = load_run(run, duration_s)
    if capture_gain is not None and capture_gain != problem.cfg.capture_gain:
        problem.sim.close()
        problem = OmniWalkProblem(dataclasses.replace(problem.cfg,
                                                      capture_gain=float(capture_gain)))
    seeds = EVAL_SEED_BASE + int(seed) * MAX_WORLDS + np.arange(int(worlds))
    engine = problem.ctl.initial_params()
    o = problem.obs_dim
    rows = {"controller": (policy.params, policy.obs_mean, policy.obs_std),
            "engine": (engine, np.zeros(o), np.ones(o))}
    out: dict[str, Any] = {"run": str(folder), "robot": problem.robot.name,
                           "worlds": int(worlds), "seed": int(seed),
                           "duration_s": float(duration_s),
                           "push_ns": list(problem.draw.push_ns),
                           "capture_gain": problem.cfg.capture_gain}
    quiet = quiet_problem(problem)
    for name, (x, mean, std) in rows.items():
        out[name] = _summary(_play(problem, x, mean, std, seeds))
        out[name]["top_speeds"] = top_speeds(quiet, x, mean, std)
    quiet.sim.close()
    problem.sim.close()
    return out


def _pct(v: float | None) -> str:
    return "–" if v is None else f"{100 * v:.0f} %"


def table(res: dict[str, Any]) -> str:
    lo, hi = res["push_ns"]
    robot = {"nao": "NAO", "op3": "OP3"}.get(res.get("robot", "nao"), res.get("robot"))
    lines = [f"{robot}, {res['worlds']} unseen perturbed worlds, {res['duration_s']:g} s of random "
             f"commands each, one push U({lo:g}, {hi:g}) N s (seed {res['seed']})"
             + (f", capture step gain {res['capture_gain']:g}" if res.get("capture_gain")
                else ""), "",
             "| controller | survival | time up (s) | speed error (m/s) | relative | steady | "
             "yaw-rate error (deg/s) | relative | steady | power (W) |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    engine = ("walk engine (the start) + capture step" if res.get("capture_gain") else
              "walk engine (open loop, the start)")
    for key, name in (("controller", "evolved controller"), ("engine", engine)):
        r = res[key]
        lines.append(f"| {name} | {100 * r['survival']:.0f} % | {r['time_up_s']:.1f} | "
                     f"{r['speed_error_mps']:.3f} | {_pct(r['relative_speed_error'])} | "
                     f"{_pct(r['steady_relative_speed_error'])} | "
                     f"{np.degrees(r['yaw_rate_error_rps']):.1f} | "
                     f"{_pct(r['relative_yaw_rate_error'])} | "
                     f"{_pct(r['steady_relative_yaw_rate_error'])} | {r['power_w']:.0f} |")
    lines += ["", f"Top speeds (nominal world, each command alone for {SPEED_TEST_S:g} s, the "
              "mean over the last half):", "",
              "| command | controller | engine |", "|---|---|---|"]
    for name, c in res["controller"]["top_speeds"].items():
        e = res["engine"]["top_speeds"][name]

        def fmt(r: dict) -> str:
            s = (f"{r['yaw_rate_dps']:.0f} deg/s" if name.startswith("turn") else
                 f"vx {r['vx_mps']:.2f}, vy {r['vy_mps']:.2f} m/s")
            if name == "stand":  # the creep: finer, and its turning too
                s = (f"vx {100 * r['vx_mps']:.1f}, vy {100 * r['vy_mps']:.1f} cm/s, "
                     f"{r['yaw_rate_dps']:.1f} deg/s")
            return s + (" (fell)" if r["fell"] else "")
        lines.append(f"| {name} {c['command']} | {fmt(c)} | {fmt(e)} |")
    return "\n".join(lines)


def compare_command(run: Path, worlds: int = 100, duration_s: float = 60.0, seed: int = 0,
                    json_out: bool = False, capture_gain: float | None = None) -> str:
    res = compare(run, worlds, duration_s, seed, capture_gain)
    return json.dumps(res, indent=1) if json_out else table(res)
