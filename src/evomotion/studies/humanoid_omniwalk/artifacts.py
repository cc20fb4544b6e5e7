"""What a humanoid-walk run leaves: the best controller as ``policy.npz``, ``policy.py``,
``policy.onnx`` and ``policy.json`` (what a robot-side loop needs: the observation columns in
order, the command and how it is ramped, the gait clock's period, the control period, the
driven joints with their nominal pose and bounds, the joint that follows another); with a
capture step (``problem.capture_gain``) also ``capture_step.py`` (the layer, standard library
only, its settings in ``policy.json``'s ``layers``), and ``naoqi/`` carries it too, and with the
``onnx`` extra ``controller.onnx`` (the policy and the layer in one ONNX graph, the layer's
state an input and an output: :mod:`evomotion.sim.robots.nao.capture_step_onnx`)."""

from __future__ import annotations

from typing import Any

POLICY_JSON = "policy.json"
CONTROLLER_ONNX = "controller.onnx"


def policy_info(problem: Any) -> dict[str, Any]:
    """The ``policy.json`` record of ``problem`` (an :class:`.problem.OmniWalkProblem`)."""
    from evomotion.sim.observations import CHANNELS

    ctl, cfg, sim = problem.ctl, problem.cfg, problem.sim
    model = problem.robot.model
    joints = [model.joint(int(model.actuator_trnid[int(c), 0])).name for c in sim.columns]
    layers = {"capture_step": {
        **capture_step_record(ctl, cfg.capture_gain), "file": "capture_step.py",
        "note": "capture-point foot placement by leg odometry on top of the policy: "
                "capture_step.py (standard library; also in naoqi/) runs it, "
                "CaptureStep(this record, observations, joints, nominal_rad, "
                "control_period_s)(obs, policy(obs)) -> action; policy.py and policy.onnx are "
                "the policy without it; controller.onnx (written with the onnx extra) is the "
                "policy and the layer in one graph", **_controller_onnx_info(ctl)}} \
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


def _controller_onnx_info(ctl: Any) -> dict[str, Any]:
    """``{"controller_onnx": its inputs, outputs and state}`` (``policy.json``'s note on
    ``controller.onnx``), or nothing without the ``onnx`` extra (no file is written then)."""
    from evomotion.sim.robots.nao.capture_step_onnx import state_layout

    try:
        import onnx  # noqa: F401
    except ImportError:
        return {}
    return {"controller_onnx": {"file": CONTROLLER_ONNX,
            "inputs": {"observation": "float32 [robots, observations]",
                       "state_in": "float64 [robots, S]: the last call's state_out"},
            "outputs": {"action": "float32 [robots, joints]: the policy's action with the "
                                  "feet moved", "state_out": "float64 [robots, S]"},
            "state_start": "zeros (a new walk)",
            "state_layout": state_layout({"bins": ctl.window})}}


def capture_step_record(ctl: Any, gain: float) -> dict[str, Any]:
    """The capture step's settings for the NAOqi runner's ``capture_step.py`` (and
    ``policy.json``): its gain and constants, the walk engine's settings, the NAO's leg
    geometry and leg joints' ranges (``ctl`` a :class:`.controller.Controller` on the NAO)."""
    from dataclasses import asdict

    from evomotion.sim.robots import nao
    from evomotion.sim.robots.nao.joint_limits import JOINT_RANGES
    from evomotion.studies.humanoid_omniwalk import capture_step as cs

    return {"gain": float(gain), "com_height_m": ctl.com_height_m,
            "deadband_mps": cs.DEADBAND_MPS, "reach_x_m": cs.REACH_X_M, "out_y_m": cs.OUT_Y_M,
            "in_y_m": cs.IN_Y_M, "calibration_rate": cs.CALIBRATION_RATE,
            "calibration_gate_mps": cs.CALIBRATION_GATE_MPS,
            "warmup_cycles": cs.WARMUP_CYCLES,
            "bins": ctl.window,
            "gait": {k: float(v) for k, v in asdict(ctl.gait).items()},
            "geometry": {"hip_offset_y_m": nao.HIP_OFFSET_Y_M,
                         "hip_offset_z_m": nao.HIP_OFFSET_Z_M, "thigh_m": nao.THIGH_M,
                         "tibia_m": nao.TIBIA_M},
            "ranges": {j: [float(v) for v in JOINT_RANGES[j]]
                       for j in (*nao.LEFT_LEG, *nao.RIGHT_LEG)}}


def write_policy(ctx: Any) -> None:
    """``policy.npz``/``.py``/``.onnx``/``.json`` of the best centre so far (every checkpoint)."""
    from evomotion.studies.policy_files import write_policy_files

    if ctx.problem is None:
        return
    info = policy_info(ctx.problem)
    write_policy_files(ctx, {POLICY_JSON: info})
    if ctx.problem.cfg.capture_gain and ctx.out_dir is not None and \
            (ctx.out_dir / "policy.npz").is_file():
        from evomotion.outfile import atomic_write_text
        from evomotion.sim.robots.nao.policy_export import CAPTURE_STEP, runner_source

        atomic_write_text(ctx.out_dir / CAPTURE_STEP, runner_source(CAPTURE_STEP))
        write_controller_onnx(ctx, info)


def controller_onnx(problem: Any, policy: Any, info: dict[str, Any] | None = None) -> Any:
    """The ``onnx.ModelProto`` of ``controller.onnx``: ``policy`` (a ``read_policy_npz``
    result) and ``problem``'s capture step (``info``: its :func:`policy_info`, if at hand)."""
    from evomotion.sim.robots.nao.capture_step_onnx import controller_model

    info = info if info is not None else policy_info(problem)
    return controller_model(policy.spec, policy.params, policy.obs_mean, policy.obs_std,
                            capture_step_record(problem.ctl, problem.cfg.capture_gain),
                            list(problem.obs_names), info["joints"], info["nominal_rad"],
                            info["control_period_s"])


def write_controller_onnx(ctx: Any, info: dict[str, Any]) -> None:
    """``controller.onnx`` beside ``policy.npz`` (the exported policy, read back, and the
    capture step; ``info`` the run's :func:`policy_info`); skipped with one note without the
    ``onnx`` extra."""
    try:
        import onnx  # noqa: F401
    except ImportError:
        if not ctx.cache.get("controller_onnx_note"):
            ctx.log("note: controller.onnx not written (pip install 'evomotion[onnx]')")
            ctx.cache["controller_onnx_note"] = True
        return
    from evomotion.core.policies.export import read_policy_npz
    from evomotion.outfile import atomic_write_bytes

    model = controller_onnx(ctx.problem, read_policy_npz(ctx.out_dir / "policy.npz"), info)
    atomic_write_bytes(ctx.out_dir / CONTROLLER_ONNX, model.SerializeToString(),
                       "ONNX controller")


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
    info = policy_info(p)
    layer = capture_step_record(p.ctl, p.cfg.capture_gain) if p.cfg.capture_gain else None
    export = p.robot.capability("naoqi_policy", "humanoid-walk's NAOqi export")
    try:
        export.write_naoqi_policy(ctx.out_dir / "naoqi", read_policy_npz(npz), p.obs_names,
                                  info["joints"], info["nominal_rad"], info["lower_rad"],
                                  info["upper_rad"], info["control_period_s"],
                                  info["phase_period_s"], info["nominal_pose_all_actuators"],
                                  command_ramp_s=p.cfg.ramp_s, capture_step=layer)
    except InputError as e:
        ctx.log(f"naoqi/ not written: {e}")
        return
    notes = export.approximations(p.obs_names)
    ctx.log("naoqi/policy_runner.py + policy.json" + (" + capture_step.py" if layer else "")
            + ": walk the NAO (Python 2.7 or 3; --command "
            "vx,vy,w or --command-key KEY)" + (f"; approximated on the robot: "
                                               f"{'; '.join(notes)}" if notes else ""))


def finalize(ctx: Any) -> int | None:
    from evomotion.studies.policy_files import log_best_centre

    write_policy(ctx)
    write_naoqi(ctx)
    log_best_centre(ctx, "humanoid-walk", ("capture_step.py", CONTROLLER_ONNX))
    return None

