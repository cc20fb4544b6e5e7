"""The walk engine by numerical leg IK (any biped): it reproduces the NAO's closed-form engine,
reaches its foot targets on the OP3 and the dm humanoid, scales to the leg, refuses a gait the
leg cannot reach in one line; the OP3's controller drives its legs and its start walks."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.sim.leg_ik import LegChain
from evomotion.sim.robots import load_robot, nao
from evomotion.sim.robots.nao.leg_ik import rot_y
from evomotion.studies.humanoid_omniwalk.ik_gait import NAO_HIP_TO_SOLE_M, IKGait, scaled
from evomotion.studies.humanoid_omniwalk.omni_gait import OmniGait, targets
from evomotion.studies.humanoid_omniwalk.problem import OmniWalkConfig, OmniWalkProblem


def _grid(period_s: float, n: int = 40):
    rng = np.random.default_rng(0)
    cmd = rng.uniform([-0.2, -0.2, -1.2], [0.45, 0.2, 1.2], (n, 3))
    return rng.uniform(0, 1, n), cmd


def test_the_nao_hip_to_sole_constant_is_the_nao_models():
    r = load_robot("nao")
    assert LegChain(r, "left", r.pose).hip_to_sole() == pytest.approx(NAO_HIP_TO_SOLE_M,
                                                                      abs=5e-5)


def test_on_the_nao_it_reproduces_the_closed_form_engine():
    """Same feet, other IK: the leg joints within 0.02 rad of omni_gait.targets (the sole sites
    sit a few mm off the ankle axis, which the closed-form engine places). Without turning: the
    closed-form engine turns both feet through the one hip yaw-pitch motor, the generic one
    solves each leg alone. The generic engine sways the other way (ik_gait's doc): a phase of
    π makes its sway the NAO engine's."""
    r = load_robot("nao")
    gait = OmniGait()
    ik = IKGait(r, replace(gait, sway_phase_rad=math.pi))
    phase, cmd = _grid(gait.period_s)
    cmd[:, 2] = 0.0
    got = ik.targets(phase, cmd)
    want = targets(gait, phase, cmd)
    col = {j: i for i, j in enumerate(nao.JOINTS)}
    legs = [col[j] for j in (*nao.LEFT_LEG, *nao.RIGHT_LEG)]
    cols = [r.joints.index(j) for j in (*nao.LEFT_LEG, *nao.RIGHT_LEG)]
    assert np.abs(got[:, cols] - want[:, legs]).max() < 0.02


@pytest.mark.parametrize("name", ["op3", "dm-humanoid"])
def test_feet_reach_their_targets_and_scale_with_the_leg(name):
    r = load_robot(name)
    gait = OmniGait()
    ik = IKGait(r, gait)
    assert ik.scale == pytest.approx(ik.hip_to_sole_m / NAO_HIP_TO_SOLE_M)
    assert ik.gait.period_s == pytest.approx(gait.period_s * math.sqrt(ik.scale))
    assert ik.gait.step_height_m == pytest.approx(gait.step_height_m * ik.scale)
    phase, cmd = _grid(ik.gait.period_s)
    q = ik.targets(phase, cmd)
    others = np.setdiff1d(np.arange(r.model.nu), ik.columns)
    assert np.array_equal(q[:, others], np.broadcast_to(r.pose[others], q[:, others].shape))
    lean = rot_y(ik.gait.lean_rad)  # torso -> the upright walk frame
    for f in ik.feet:  # the solved legs put the soles where the engine wants them
        sole, _, _, _ = f.leg.fk(q[:, f.leg.columns])
        # a foot in swing is higher than in stance, by at most the step height
        up = (sole @ lean.T)[:, 2]
        up = up - up.min()
        assert up.max() <= ik.gait.step_height_m + 1e-4 and up.max() > 0.5 * \
            ik.gait.step_height_m
    # zero command: the feet step in place, no travel
    still = ik.targets(np.linspace(0, 1, 20, endpoint=False), np.zeros((20, 3)))
    for f in ik.feet:
        sole, _, _, _ = f.leg.fk(still[:, f.leg.columns])
        assert np.ptp((sole @ lean.T)[:, 0]) < 1e-4


def test_a_gait_the_leg_cannot_reach_is_one_line():
    r = load_robot("op3")
    ik = IKGait(r, OmniGait(period_s=1.5))  # 0.45 m/s over a 1.5 s cycle: too long a step
    with pytest.raises(InputError, match="misses its gait target by") as e:
        ik.targets(np.array([0.0, 0.25]), np.array([[0.45, 0, 0], [0.45, 0, 0]]))
    assert "\n" not in str(e.value)


def test_scaled_keeps_angles_and_fractions():
    g = scaled(OmniGait(), 4.0)
    assert g.period_s == pytest.approx(0.96) and g.sway_m == pytest.approx(0.1)
    assert g.lean_rad == OmniGait().lean_rad and g.swing_fraction == OmniGait().swing_fraction


def test_the_op3_controller_drives_its_legs_and_its_start_walks_forward():
    """The OP3 (`problem.robot`): 12 leg joints driven, no follower, no speed limits known;
    the fitted engine walks forward in the nominal world without falling."""
    from evomotion.studies.humanoid_omniwalk.commands import tracking

    p = OmniWalkProblem(OmniWalkConfig(robot="op3", duration_s=4.0, threads=1, perturb=False,
                                       push_max_ns=0.0))
    ctl = p.ctl
    assert len(ctl.driven) == 12 and all("hip" in j or "knee" in j or "ank" in j
                                         for j in ctl.driven)
    assert np.isinf(ctl.speed_limits).all()
    x0 = ctl.initial_params()
    C = math.ceil(p.nstep / p.control_steps)
    cmd = np.tile([0.2, 0.0, 0.0], (1, C, 1)) * np.clip(np.arange(C) * 0.02 / 0.5, 0, 1)[
        None, :, None]
    m, res, _ = p.play(x0[None], np.zeros((1, p.obs_dim)), np.ones((1, p.obs_dim)),
                       np.zeros(1, int), push_ns=0.0, commands=cmd)
    assert not res.fell.any()
    tr = tracking(res.torso, cmd, ctl.window, ctl.control_dt)
    assert tr.vx[0, -75:].mean() > 0.12


def test_an_unknown_robot_is_one_line():
    with pytest.raises(InputError, match="robot") as e:
        OmniWalkProblem(OmniWalkConfig(robot="no-such-robot"))
    assert "\n" not in str(e.value)


def test_an_op3_run_leaves_its_controller_and_compares(tmp_path):
    """`--robot op3` through the run loop: policy files for the OP3 (no NAOqi runner: that is
    the NAO's), compare names the robot."""
    import json
    import subprocess
    import sys

    from evomotion.studies import get_study
    from evomotion.studies.humanoid_omniwalk.compare import compare, table

    out = tmp_path / "op3"
    smoke = [a for s in get_study("humanoid-walk").smoke for a in ("--set", s)]
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "humanoid-walk",
                        "--robot", "op3", "--out", str(out), *smoke, "--set",
                        "run.generations=1", "--set", "run.videos=false", "--quiet"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    info = json.loads((out / "policy.json").read_text())
    assert info["robot"] == "op3" and info["followers"] == {} and len(info["joints"]) == 12
    assert (out / "policy.onnx").is_file() and not (out / "naoqi").exists()
    res = compare(out, worlds=2, duration_s=1.0)
    assert res["robot"] == "op3" and table(res).startswith("OP3, 2 unseen")
