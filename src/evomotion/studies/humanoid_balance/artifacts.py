"""What a humanoid-balance run leaves: the best centre as ``policy.npz``, ``policy.py``,
``policy.onnx`` (as the gym study's) and ``policy.json``, what a robot-side loop needs to feed
it: the robot, the observation columns in order, the control period, the driven joints with
their nominal pose and target bounds (``target = clip(nominal + action, lower, upper)``)."""

from __future__ import annotations

from typing import Any

POLICY_JSON = "policy.json"


def policy_info(problem: Any) -> dict[str, Any]:
    """The ``policy.json`` record of ``problem`` (a :class:`.problem.HumanoidBalanceProblem`)."""
    from evomotion.sim.observations import CHANNELS

    r, sim, cfg = problem.robot, problem.sim, problem.cfg
    model = r.model
    joints = [model.joint(int(model.actuator_trnid[int(c), 0])).name for c in sim.columns]
    return {
        "robot": r.name, "policy": problem.policy.kind,
        "files": {"npz": "policy.npz", "py": "policy.py", "onnx": "policy.onnx"},
        "observation_channels": list(problem.obs_spec.channels),
        "observations": list(problem.obs_names),
        "channel_meaning": {c: CHANNELS[c] for c in problem.obs_spec.channels},
        "control_period_s": cfg.control_period_s, "physics_dt_s": problem.dt,
        "control_steps": problem.control_steps,
        "action": "offset (rad) from the nominal pose of each joint, in this order; "
                  "target = clip(nominal + action, lower, upper)",
        "joints": joints,
        "nominal_rad": [float(v) for v in sim.nominal[sim.columns]],
        "lower_rad": [float(v) for v in sim.lower], "upper_rad": [float(v) for v in sim.upper],
        "other_actuators": "hold the nominal pose",
        "nominal_pose_all_actuators": {model.actuator(i).name: float(sim.nominal[i])
                                       for i in range(model.nu)},
        "foot_contact_order": list(r.feet),
    }


def write_policy(ctx: Any) -> None:
    """``policy.npz``/``.py``/``.onnx``/``.json`` of the best centre so far (every checkpoint)."""
    from evomotion.studies.policy_files import write_policy_files

    if ctx.problem is not None:
        write_policy_files(ctx, {POLICY_JSON: policy_info(ctx.problem)})


def write_naoqi(ctx: Any) -> None:
    """``naoqi/`` beside ``policy.npz`` (``policy_runner.py`` + its ``policy.json``) through the
    robot's ``naoqi_policy`` capability (the NAO); a policy the NAO cannot run (it reads a
    channel no NAO sensor measures) is one log line, not a failed run."""
    from evomotion.core.policies.export import read_policy_npz
    from evomotion.errors import InputError

    p = ctx.problem
    npz = ctx.out_dir / "policy.npz" if ctx.out_dir is not None else None
    if p is None or npz is None or not npz.is_file() or not p.robot.has("naoqi_policy"):
        return
    info = policy_info(p)
    export = p.robot.capability("naoqi_policy", "humanoid-balance's NAOqi export")
    try:
        export.write_naoqi_policy(ctx.out_dir / "naoqi", read_policy_npz(npz), p.obs_names,
                                  info["joints"], info["nominal_rad"], info["lower_rad"],
                                  info["upper_rad"], p.cfg.control_period_s,
                                  p.obs_spec.phase_period_s, info["nominal_pose_all_actuators"])
    except InputError as e:
        ctx.log(f"naoqi/ not written: {e}")
        return
    notes = export.approximations(p.obs_names)
    ctx.log("naoqi/policy_runner.py + policy.json: run the policy on a NAO (Python 2.7 or 3)"
            + (f"; approximated on the robot: {'; '.join(notes)}" if notes else ""))


def finalize(ctx: Any) -> int | None:
    from evomotion.studies.policy_files import log_best_centre

    write_policy(ctx)
    write_naoqi(ctx)
    log_best_centre(ctx, "humanoid-balance")
    return None

