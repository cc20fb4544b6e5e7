"""The NAOqi runner walks the omnidirectional controller as the simulator does: a closed-loop
NAO episode of the controller (the fitted engine plus random feedback gains, latency 0, no
push) under a command is recorded per control step; the runner, fed ALMemory values derived
from the recorded states and the command (fixed with ``--command`` or changed through an
ALMemory key), ramps the command as in training and sends the simulator's joint targets to
1e-6. No NAO is here: this checks the runner's arithmetic, its sensor layout, its command
ramp and its DCM calls, not the real robot's sensors, timing or walking."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent.parent / "humanoid_balance"))
import fake_naoqi  # noqa: E402
from test_naoqi_runner import PERIOD_S, _frame, _load_runner, _Offset  # noqa: E402

from evomotion.core.policies.export import export_policy, read_policy_npz  # noqa: E402
from evomotion.sim.robots.nao.policy_export import write_naoqi_policy  # noqa: E402
from evomotion.sim.worlds import World  # noqa: E402
from evomotion.studies.humanoid_omniwalk.artifacts import policy_info  # noqa: E402
from evomotion.studies.humanoid_omniwalk.problem import (  # noqa: E402
    OmniWalkConfig,
    OmniWalkProblem,
)

KEY = "evomotion/walk_command"
A, B = [0.2, 0.05, 0.3], [-0.1, 0.0, -0.6]


def _walk(tmp_path, change_step: int | None, command_feedback: bool = False):
    """(naoqi folder, frames, simulator targets, commands seen) of a 1.6 s walk."""
    p = OmniWalkProblem(OmniWalkConfig(duration_s=1.6, threads=1,
                                       command_feedback=command_feedback))
    m = p.robot.model
    rng = np.random.default_rng(4)
    (tape, _), (gain, _), *fed = p.policy.unflatten(p.ctl.initial_params())
    gain = gain + rng.normal(0, 0.001, gain.shape)
    mean, std = rng.normal(0, 0.1, p.obs_dim), rng.uniform(0.5, 2.0, p.obs_dim)
    # the NAO has no joint velocity sensor: the runner differences positions, so the gains on
    # joint_vel are 0 here (what is compared is everything else)
    vel = [i for i, n in enumerate(n for k, n in enumerate(p.obs_names)
                                   if k in set(p.policy.feedback_columns))
           if n.startswith("joint_vel")]
    layers = [(tape, None), (gain, None)]
    if fed:  # command feedback: the tape reads c + G x
        G = rng.normal(0, 0.01, fed[0][0].shape)
        layers.append((G, None))
    for W, _ in layers[1:]:
        W[:, vel] = 0.0
    params = p.policy.flatten(layers)
    C = math.ceil(p.nstep / p.control_steps)
    t = np.arange(C) * PERIOD_S
    ramp = p.cfg.ramp_s
    cmd = np.array(A)[None] * np.clip(t / ramp, 0, 1)[:, None]
    if change_step is not None:
        t1 = t[change_step]
        cmd = np.where((t >= t1)[:, None], np.array(A) + (np.array(B) - A)
                       * np.clip((t - t1) / ramp, 0, 1)[:, None], cmd)
    seen = []

    def act(rows, obs):
        seen.append(obs[0].copy())
        return p.policy.act(params[None], obs, mean, std)

    res = p.sim.run(act, [World(m)], p.nstep, commands=cmd[None],
                    initial_state=p.ctl.state0, record_states=True, record_targets=True)
    assert not res.fell[0]
    export_policy(tmp_path, p.policy, params, mean, std, ("npz",))
    info = policy_info(p)
    write_naoqi_policy(tmp_path / "naoqi", read_policy_npz(tmp_path / "policy.npz"),
                       p.obs_names, info["joints"], info["nominal_rad"], info["lower_rad"],
                       info["upper_rad"], PERIOD_S, info["phase_period_s"],
                       info["nominal_pose_all_actuators"], command_ramp_s=ramp)
    contact = [p.sim.observe.slices["foot_contact"].start + i for i in range(2)]
    joints = [m.joint(int(m.actuator_trnid[c, 0])).name for c in p.robot.columns]
    frames = [_frame(m, joints, res.states[0, c], seen[c][contact]) for c in range(C)]
    for c, f in enumerate(frames):
        f[KEY] = list(B) if change_step is not None and c >= change_step else list(A)
    p.sim.close()
    return tmp_path / "naoqi", frames, res.targets[0], np.array(seen)[:, -3:]


@pytest.mark.parametrize(("change_step", "command_feedback"),
                         [(None, False), (40, False), (40, True)])
def test_runner_walks_the_simulators_targets(change_step, command_feedback, tmp_path,
                                             monkeypatch):
    folder, frames, targets, commands = _walk(tmp_path, change_step, command_feedback)
    clock = fake_naoqi.FakeClock(50.0)
    naoqi = fake_naoqi.install(clock=clock)
    monkeypatch.setitem(sys.modules, "naoqi", naoqi)
    mod = _load_runner(folder)
    record = json.loads((folder / "policy.json").read_text())
    assert record["command_ramp_s"] == 0.5 and len(record["command_columns"]) == 3
    assert ("command_gain" in record) == command_feedback
    assert "joint_vel" in record["approximated"]
    kw = ({"command": A} if change_step is None else {"command_key": KEY})
    runner = mod.Runner(record, naoqi.memory, naoqi.dcm, naoqi.motion, clock=clock,
                        sleep=clock.sleep, **kw)
    runner.start()
    naoqi.memory.stream = frames
    naoqi.memory.clock, naoqi.memory.period_s = _Offset(clock, 50.0), PERIOD_S
    steps, late = runner.run(len(frames) * PERIOD_S - 1e-9, PERIOD_S)
    assert (steps, late) == (len(frames), 0)
    sent = np.array([v for _, v in naoqi.dcm.sent])
    np.testing.assert_allclose(sent, targets, rtol=0, atol=1e-6)
    assert np.ptp(targets, axis=0).max() > 0.1  # it walked
    assert "LHipYawPitch" in record["joints"] and "RHipYawPitch" not in record["joints"]
    if change_step is not None:
        assert KEY in naoqi.memory.calls[0] and np.ptp(commands[:, 2]) > 0.8


def test_a_bad_command_key_value_keeps_the_last_command(tmp_path):
    import importlib.util

    src = Path(__file__).parents[3] / "src/evomotion/sim/robots/nao/policy_runner.py"
    spec = importlib.util.spec_from_file_location("runner_for_keys", src)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    last = [0.1, 0.0, 0.2]
    assert mod._command(None, last) == last and mod._command([1, 2], last) == last
    assert mod._command([1, float("nan"), 0], last) == last
    assert mod._command([0.3, 0.1, -0.2, 9], last) == [0.3, 0.1, -0.2]
    ramp = mod.CommandRamp(0.5)
    assert ramp([0.4, 0, 0], 10.0) == [0.0, 0.0, 0.0]
    assert ramp([0.4, 0, 0], 10.25) == pytest.approx([0.2, 0, 0])
    assert ramp([0.0, 0, 0], 10.25) == pytest.approx([0.2, 0, 0])  # a new target: from here
    assert ramp([0.0, 0, 0], 11.0) == [0.0, 0.0, 0.0]
