"""The NAOqi policy runner against a fake NAOqi fed with the simulation's sensor stream: a
humanoid-balance policy's closed-loop NAO episode (pushed, latency 0) is recorded per control
step; the runner, reading ALMemory values derived from the recorded states, sends the same
joint targets as the simulator to 1e-6. No NAO is here: this checks the runner's arithmetic,
its sensor layout and its DCM calls, not the real robot's sensors or timing."""

from __future__ import annotations

import importlib.util
import json
import math
import sys

import fake_naoqi
import numpy as np
import pytest

from evomotion.core.policies import make_policy
from evomotion.core.policies.export import export_policy, read_policy_npz
from evomotion.sim.closed_loop import ClosedLoopSimulator
from evomotion.sim.observations import ObservationSpec
from evomotion.sim.robots import load_robot
from evomotion.sim.robots.nao.policy_export import (
    CONTACT_THRESHOLD_KG,
    PITCH_KEY,
    ROLL_KEY,
    fsr_key,
    joint_key,
    write_naoqi_policy,
)
from evomotion.sim.state import QPOS_OFFSET
from evomotion.studies.humanoid_balance.episodes import WorldDraw, episode_world

CHANNELS = ("joint_pos", "gyro", "gravity", "roll_pitch", "foot_contact", "phase")
#: the structured policy's test reads these (its tape reads phase raw, its gains the rest)
STRUCTURED_CHANNELS = ("joint_pos", "gyro", "gravity", "foot_contact", "phase")
PERIOD_S, K, PHASE_S = 0.02, 5, 0.5
IMU = "Device/SubDeviceList/InertialSensor"


def _load_runner(folder):
    spec = importlib.util.spec_from_file_location("exported_policy_runner",
                                                  folder / "policy_runner.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _episode(kind: str, seed: int, tmp_path):
    """A pushed closed-loop NAO episode of a random humanoid-balance-style policy: (exported
    folder, per control step the ALMemory frame, the simulator's targets)."""
    robot = load_robot("nao")
    m = robot.model
    channels = STRUCTURED_CHANNELS if kind == "structured" else CHANNELS
    spec_obs = ObservationSpec(channels, phase_period_s=PHASE_S)
    sim = ClosedLoopSimulator(robot, spec_obs, K, 1)
    nominal = np.asarray(robot.pose, float)[sim.columns]
    options: dict = {"hidden": (8, 6)} if kind == "mlp" else {}
    if kind == "structured":
        phase = sim.observe.slices["phase"]
        options = {"harmonics": 2, "phase_columns": (phase.start, phase.start + 1)}
    policy = make_policy(kind, sim.observation_size, sim.action_size, scale=0.3,
                         low=sim.lower - nominal, high=sim.upper - nominal, clip_obs=5.0,
                         **options)
    rng = np.random.default_rng(seed)
    params = rng.normal(0.0, 0.3, policy.n_params)
    mean = rng.normal(0.0, 0.1, policy.obs_dim)
    std = rng.uniform(0.05, 1.0, policy.obs_dim)
    seen: list[np.ndarray] = []

    def act(rows, obs):
        seen.append(obs[0].copy())
        return policy.act(params[None], obs, mean, std)

    world = episode_world(m, WorldDraw((3.0, 3.0), (0.1, 0.1), 0.8, perturb=False), seed)
    assert world.latency_steps == 0
    res = sim.run(act, [world], int(0.8 / m.opt.timestep), record_states=True,
                  record_targets=True)
    sim.close()
    steps = int(math.ceil(res.steps[0] / K))
    export_policy(tmp_path, policy, params, mean, std, ("npz",))
    joints = [m.joint(int(m.actuator_trnid[c, 0])).name for c in sim.columns]
    write_naoqi_policy(tmp_path / "naoqi", read_policy_npz(tmp_path / "policy.npz"),
                       sim.observe.names, joints, nominal, sim.lower, sim.upper, PERIOD_S,
                       PHASE_S, {m.actuator(i).name: float(sim.nominal[i]) for i in range(m.nu)})
    contact = [sim.observe.slices["foot_contact"].start + i for i in range(2)]
    frames = [_frame(m, joints, res.states[0, c], seen[c][contact]) for c in range(steps)]
    return tmp_path / "naoqi", frames, res.targets[0, :steps], np.array(seen)[:, contact]


def _frame(m, joints, state, contacts) -> dict[str, float]:
    """ALMemory values of one recorded state: joint angles, gyro, AngleX/Y (ZYX roll/pitch by
    the textbook formulas), and FSR weights (the contact the simulator's policy saw, which
    MuJoCo computed one physics step before the recorded state)."""
    frame = {joint_key(j): float(state[QPOS_OFFSET + m.jnt_qposadr[m.joint(j).id]])
             for j in joints}
    w, x, y, z = state[QPOS_OFFSET + 3:QPOS_OFFSET + 7]
    frame[ROLL_KEY] = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    frame[PITCH_KEY] = math.asin(max(-1.0, min(1.0, 2 * (w * y - x * z))))
    gyro = state[QPOS_OFFSET + m.nq + 3:QPOS_OFFSET + m.nq + 6]
    for axis, value in zip("XYZ", gyro, strict=True):
        frame[f"{IMU}/Gyroscope{axis}/Sensor/Value"] = float(value)
    for foot, c in zip(("LFoot", "RFoot"), contacts, strict=True):
        frame[fsr_key(foot)] = 2.6 if c else 0.05
    return frame


@pytest.mark.parametrize("kind, seed", [("linear", 3), ("mlp", 4), ("structured", 7)])
def test_runner_sends_the_simulators_targets(kind, seed, tmp_path, monkeypatch):
    folder, frames, targets, contacts = _episode(kind, seed, tmp_path)
    assert len(frames) >= 20 and contacts.min() == 0 and contacts.max() == 1
    clock = fake_naoqi.FakeClock(100.0)  # the runner's clock starts anywhere
    naoqi = fake_naoqi.install(clock=clock)
    monkeypatch.setitem(sys.modules, "naoqi", naoqi)
    runner_mod = _load_runner(folder)
    record = json.loads((folder / "policy.json").read_text())
    assert record["kind"] == kind and ("layers" in record) == (kind != "structured")
    runner = runner_mod.Runner(record, naoqi.memory, naoqi.dcm, naoqi.motion,
                               clock=clock, sleep=clock.sleep)
    runner.start()
    assert set(naoqi.motion.stiffness.values()) == {1.0} and len(naoqi.motion.poses) == 1
    naoqi.memory.stream = frames
    naoqi.memory.clock, naoqi.memory.period_s = _Offset(clock, 100.0), PERIOD_S
    steps, late = runner.run(len(frames) * PERIOD_S - 1e-9, PERIOD_S)
    assert (steps, late) == (len(frames), 0)
    assert all(len(c) == len(naoqi.memory.calls[0]) for c in naoqi.memory.calls)  # one read
    sent = np.array([v for _, v in naoqi.dcm.sent])
    np.testing.assert_allclose(sent, targets, rtol=0, atol=1e-6)
    assert np.abs(sent - targets).max() < 1e-9  # in fact to rounding
    assert np.ptp(targets, axis=0).max() > 0.05  # the policy really moved the legs
    times = [t for t, _ in naoqi.dcm.sent]
    assert np.all(np.diff(times) == 20)


class _Offset:
    """The fake clock less its start: the frame index of the runner's time."""

    def __init__(self, clock, t0):
        self.clock, self.t0 = clock, t0

    @property
    def t(self):
        return self.clock.t - self.t0


def test_dry_run_through_main_sends_nothing(tmp_path, monkeypatch, capsys):
    folder, frames, _, _ = _episode("linear", 5, tmp_path)
    naoqi = fake_naoqi.install(frames[0])
    monkeypatch.setitem(sys.modules, "naoqi", naoqi)
    runner_mod = _load_runner(folder)
    assert runner_mod.main([str(folder / "policy.json"), "--seconds", "0.04", "--period-ms",
                            "20", "--dry-run", "--ip", "10.0.0.7"]) == 0
    out = capsys.readouterr()
    lines = out.out.strip().splitlines()
    assert len(lines) == 2 and len(lines[0].split(",")) == 10
    assert not naoqi.dcm.sent and not naoqi.dcm.aliases and not naoqi.motion.stiffness
    assert ("ALMemory", "10.0.0.7", 9559) in naoqi.connections
    assert runner_mod.main([str(folder / "policy.json"), "--period-ms", "50"]) == 1
    assert "10 to 20" in capsys.readouterr().err


def test_ctrl_c_holds_the_last_targets(tmp_path, monkeypatch):
    folder, frames, _, _ = _episode("linear", 6, tmp_path)
    clock = fake_naoqi.FakeClock()
    naoqi = fake_naoqi.install(frames[0], clock)
    runner_mod = _load_runner(folder)
    record = json.loads((folder / "policy.json").read_text())
    runner = runner_mod.Runner(record, naoqi.memory, naoqi.dcm, naoqi.motion, clock=clock,
                               sleep=clock.sleep)
    runner.start()

    def interrupt(targets):
        if len(naoqi.dcm.sent) == 3:
            raise KeyboardInterrupt

    assert runner.run(10.0, PERIOD_S, interrupt) == (3, 0)
    assert len(naoqi.dcm.sent) == 3 and set(naoqi.motion.stiffness.values()) == {1.0}
    assert runner.last_targets == naoqi.dcm.sent[-1][1]
    assert CONTACT_THRESHOLD_KG < 2.6


def test_a_policy_the_nao_cannot_run_is_one_log_line_not_a_failed_run(tmp_path):
    from types import SimpleNamespace

    from evomotion.studies.humanoid_balance.artifacts import write_naoqi
    from evomotion.studies.humanoid_balance.problem import (
        HumanoidBalanceConfig,
        HumanoidBalanceProblem,
    )

    lines: list[str] = []
    for channels in ("joint_pos,gyro,torso_height", "joint_pos,gyro"):
        p = HumanoidBalanceProblem(HumanoidBalanceConfig(observations=channels, threads=1))
        out = tmp_path / channels.replace(",", "_")
        out.mkdir()
        export_policy(out, p.policy, np.zeros(p.policy.n_params), np.zeros(p.obs_dim),
                      np.ones(p.obs_dim), ("npz",))
        write_naoqi(SimpleNamespace(problem=p, out_dir=out, log=lines.append))
        assert (out / "naoqi" / "policy.json").is_file() == ("torso" not in channels)
    assert lines[0] == ("naoqi/ not written: NAOqi export: the policy reads torso_height, which "
                        "no NAO sensor measures (the torso's height above the floor); evolve "
                        "it without them")
    assert lines[1].startswith("naoqi/policy_runner.py + policy.json") and "approx" not in lines[1]


def test_a_structured_run_writes_its_naoqi_folder(tmp_path):
    """humanoid-balance's own export path: a structured policy's naoqi/ is written (no longer
    refused) with the problem's phase columns, and its runner runs it on the fake NAOqi."""
    from types import SimpleNamespace

    from evomotion.studies.humanoid_balance.artifacts import write_naoqi
    from evomotion.studies.humanoid_balance.problem import (
        HumanoidBalanceConfig,
        HumanoidBalanceProblem,
    )

    p = HumanoidBalanceProblem(HumanoidBalanceConfig(
        policy="structured", observations="joint_pos,gyro,phase", harmonics=1,
        phase_period_s=0.5, threads=1))
    params = np.random.default_rng(8).normal(0, 0.1, p.policy.n_params)
    export_policy(tmp_path, p.policy, params, np.zeros(p.obs_dim), np.ones(p.obs_dim), ("npz",))
    lines: list[str] = []
    write_naoqi(SimpleNamespace(problem=p, out_dir=tmp_path, log=lines.append))
    assert lines[0].startswith("naoqi/policy_runner.py + policy.json")
    record = json.loads((tmp_path / "naoqi" / "policy.json").read_text())
    names = [c["name"] for c in record["observation"]]
    assert record["kind"] == "structured" and record["harmonics"] == 1
    assert [names[c] for c in record["phase_columns"]] == ["phase:sin", "phase:cos"]
    naoqi = fake_naoqi.install({k: 0.0 for k in _load_runner(tmp_path / "naoqi").Observer(
        record).keys})
    runner = _load_runner(tmp_path / "naoqi").Runner(record, naoqi.memory, naoqi.dcm,
                                                     naoqi.motion, clock=naoqi.clock,
                                                     sleep=naoqi.clock.sleep)
    runner.start()
    assert runner.run(0.1, record["control_period_s"]) == (5, 0)
    assert len(naoqi.dcm.sent) == 5 and len(naoqi.dcm.sent[0][1]) == p.act_dim
