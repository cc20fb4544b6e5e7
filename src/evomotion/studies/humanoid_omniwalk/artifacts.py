"""What a humanoid-walk run leaves: the best controller as ``policy.npz``, ``policy.py``,
``policy.onnx`` and ``policy.json`` (what a robot-side loop needs: the observation columns in
order, the command and how it is ramped, the gait clock's period, the control period, the
driven joints with their nominal pose and bounds, the joint that follows another)."""

from __future__ import annotations

from typing import Any

POLICY_JSON = "policy.json"


def policy_info(problem: Any) -> dict[str, Any]:
    """The ``policy.json`` record of ``problem`` (an :class:`.problem.OmniWalkProblem`)."""
    from evomotion.sim.observations import CHANNELS

    ctl, cfg, sim = problem.ctl, problem.cfg, problem.sim
    model = problem.robot.model
    joints = [model.joint(int(model.actuator_trnid[int(c), 0])).name for c in sim.columns]
    layers = {"capture_step": {
        "gain": cfg.capture_gain, "com_height_m": ctl.com_height_m,
        "note": "capture-point foot placement by leg odometry on top of the policy "
                "(evomotion.studies.humanoid_omniwalk.capture_step); not in policy.py or "
                "policy.onnx (they play the policy without it); no naoqi/ is written"}} \
        if cfg.capture_gain else {}
    return {
        "robot": problem.robot.name, "policy": problem.policy.kind,
        "files": {"npz": "policy.npz", "py": "policy.py", "onnx": "policy.onnx"},
        "observation_channels": list(problem.obs_spec.channels),
        "observations": list(problem.obs_names),
        "channel_meaning": {c: CHANNELS[c] for c in problem.obs_spec.channels},
        "command": ["vx (m/s, forward)", "vy (m/s, left)", "yaw rate (rad/s, counter-"
                    "clockwise)"],
        "command_ranges": {"vx": [cfg.vx_min, cfg.vx_max], "vy": [-cfg.vy_max, cfg.vy_max],
                           "yaw_rate": [-cfg.yaw_rate_max, cfg.yaw_rate_max]},
        "command_ramp_s": cfg.ramp_s,
        "phase_period_s": ctl.gait.period_s,
        "control_period_s": ctl.control_dt, "physics_dt_s": problem.dt,
        "control_steps": problem.control_steps,
        "action": "offset (rad) from the nominal pose of each joint, in this order; "
                  "target = clip(nominal + action, lower, upper)",
        "joints": joints,
        "followers": dict(ctl.followers),
        "nominal_rad": [float(v) for v in sim.nominal[sim.columns]],
        "lower_rad": [float(v) for v in sim.lower], "upper_rad": [float(v) for v in sim.upper],
        "other_actuators": "hold the nominal pose",
        "nominal_pose_all_actuators": {model.actuator(i).name: float(sim.nominal[i])
                                       for i in range(model.nu)},
        "foot_contact_order": list(problem.robot.feet),
        **({"layers": layers} if layers else {}),
    }


def write_policy(ctx: Any) -> None:
    """``policy.npz``/``.py``/``.onnx``/``.json`` of the best centre so far (every checkpoint)."""
    from evomotion.studies.policy_search import write_policy_files

    if ctx.problem is not None:
        write_policy_files(ctx, {POLICY_JSON: policy_info(ctx.problem)})


def write_naoqi(ctx: Any) -> None:
    """``naoqi/`` beside ``policy.npz``: ``policy_runner.py`` (Python 2.7 or 3, standard library
    only) and its ``policy.json``, the command ramp included; run it with ``--command vx,vy,w``
    or ``--command-key KEY`` (an ALMemory key a behaviour writes)."""
    from evomotion.core.policies.export import read_policy_npz
    from evomotion.errors import InputError

    p = ctx.problem
    npz = ctx.out_dir / "policy.npz" if ctx.out_dir is not None else None
    if p is None or npz is None or not npz.is_file() or not p.robot.has("naoqi_policy"):
        return
    if p.cfg.capture_gain:
        ctx.log("naoqi/ not written: the runner does not run the capture step "
                "(problem.capture_gain) this controller was evolved with")
        return
    info = policy_info(p)
    export = p.robot.capability("naoqi_policy", "humanoid-walk's NAOqi export")
    try:
        export.write_naoqi_policy(ctx.out_dir / "naoqi", read_policy_npz(npz), p.obs_names,
                                  info["joints"], info["nominal_rad"], info["lower_rad"],
                                  info["upper_rad"], info["control_period_s"],
                                  info["phase_period_s"], info["nominal_pose_all_actuators"],
                                  command_ramp_s=p.cfg.ramp_s)
    except InputError as e:
        ctx.log(f"naoqi/ not written: {e}")
        return
    notes = export.approximations(p.obs_names)
    ctx.log("naoqi/policy_runner.py + policy.json: walk the NAO (Python 2.7 or 3; --command "
            "vx,vy,w or --command-key KEY)" + (f"; approximated on the robot: "
                                               f"{'; '.join(notes)}" if notes else ""))


def finalize(ctx: Any) -> int | None:
    from evomotion.studies.policy_search import log_best_centre

    write_policy(ctx)
    write_naoqi(ctx)
    log_best_centre(ctx, "humanoid-walk")
    return None

