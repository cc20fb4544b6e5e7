"""Closed-loop policies exported for a real NAO: ``naoqi/policy_runner.py`` + ``policy.json``.

:func:`write_naoqi_policy` takes an exported policy (``policy.npz`` read back with
:func:`~evomotion.core.policies.export.read_policy_npz`), the run's observation names
(:func:`~evomotion.sim.observations.observation_names`: ``channel:item``) and the driven
joints with their nominal pose and target bounds, and writes a folder with
:mod:`.policy_runner` (a standard-library script for NAOqi 2.8's Python 2.7 or Python 3) and
the ``policy.json`` it reads (:data:`FORMAT`):

- the policy's ``kind``, normaliser, ``clip_obs``, action map (``null``: no bound / no
  clipping) and, for linear and MLP policies, a generic layer list (``policy.npz``'s arrays:
  ``{"weight": [[out][in]], "bias": [out] | null, "activation": "tanh" | "none"}``), for a
  structured one (a Fourier tape of the raw phase plus linear feedback) its ``harmonics``,
  ``phase_columns`` (the observation's ``phase:sin``/``phase:cos``), ``tape_coef`` and
  ``feedback_gain`` (:func:`structured_record`);
- per observation column its source on the NAO: an ALMemory key (``joint_pos``:
  ``Device/SubDeviceList/<J>/Position/Sensor/Value``; ``gyro``:
  ``.../InertialSensor/Gyroscope{X,Y,Z}/Sensor/Value``; ``roll_pitch``: ``.../AngleX``,
  ``.../AngleY``), ``gravity`` (from AngleX/AngleY), ``contact`` (the foot's
  ``FSR/TotalWeight`` above :data:`CONTACT_THRESHOLD_KG`), ``diff`` (``joint_vel``: the NAO
  measures no joint velocity; a finite difference of the positions, an approximation),
  the runner's clock (``phase``), ``--command`` (``command``);
- the joints (DCM ``Position/Actuator`` keys), nominal pose, bounds, control period, and the
  whole nominal pose (ALMotion names) the robot goes to before the loop;
- for a walk controller with a capture step, its ``capture_step`` record (gain, the walk
  engine's settings, the NAO's leg geometry and leg ranges), and the folder gets
  :mod:`.naoqi_capture_step` as ``capture_step.py``.

A policy reading ``torso_velocity`` or ``torso_height`` (no NAO sensor measures them) is
refused with one :class:`~evomotion.errors.InputError` line naming them, and so is an action
on ``RHipYawPitch`` (the NAO has one hip yaw-pitch motor, driven as ``LHipYawPitch``).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.core.policies.export import ExportedPolicy, policy_arrays
from evomotion.errors import InputError
from evomotion.outfile import atomic_write_text, write_json
from evomotion.sim.robots.nao import naoqi_capture_step
from evomotion.textio import decode_utf8, read_file_bytes

FORMAT = "evomotion-naoqi-policy/1"
RUNNER = "policy_runner.py"
CAPTURE_STEP = "capture_step.py"
_SOURCES = {RUNNER: RUNNER, CAPTURE_STEP: "naoqi_capture_step.py"}
#: the observations the walk's capture step reads (:mod:`.naoqi_capture_step`'s)
CAPTURE_STEP_READS = naoqi_capture_step.READS
POLICY_JSON = "policy.json"
#: a foot touches the floor when its FSRs carry more than this (kg; an assumption: the NAO
#: standing puts ~2.6 kg on each foot, a swing foot ~0)
CONTACT_THRESHOLD_KG = 0.3
UNMEASURED = {"torso_velocity": "the torso's linear velocity",
              "torso_height": "the torso's height above the floor"}
APPROXIMATED = {"joint_vel": "finite difference of the joint angles over the measured period "
                             "(the NAO has no joint velocity sensor)"}
_DEV = "Device/SubDeviceList"
_IMU = f"{_DEV}/InertialSensor"
#: the NAO's feet (its spec's ``[feet]`` roles, or the FSR groups' names) -> FSR group
FEET = {"left": "LFoot", "right": "RFoot", "LFoot": "LFoot", "RFoot": "RFoot"}
ROLL_KEY, PITCH_KEY = f"{_IMU}/AngleX/Sensor/Value", f"{_IMU}/AngleY/Sensor/Value"


def joint_key(joint: str) -> str:
    """The ALMemory key of a joint's measured angle (rad)."""
    return f"{_DEV}/{joint}/Position/Sensor/Value"


def fsr_key(foot: str) -> str:
    """The ALMemory key of a foot's FSR total weight (kg); ``foot``: ``LFoot``/``RFoot``."""
    return f"{_DEV}/{foot}/FSR/TotalWeight/Sensor/Value"


def observation_sources(names: Sequence[str]) -> list[dict[str, Any]]:
    """Each observation column's source on the NAO (see the module doc)."""
    bad = sorted({n.split(":", 1)[0] for n in names} & set(UNMEASURED))
    if bad:
        raise InputError(f"NAOqi export: the policy reads {', '.join(bad)}, which no NAO sensor "
                         f"measures ({'; '.join(UNMEASURED[b] for b in bad)}); evolve it "
                         "without them")
    out = []
    for name in names:
        channel, _, item = name.partition(":")
        col: dict[str, Any] = {"name": name}
        if channel == "joint_pos":
            col.update(source="memory", key=joint_key(item))
        elif channel == "joint_vel":
            col.update(source="diff", key=joint_key(item))
        elif channel == "gyro" and item in ("x", "y", "z"):
            col.update(source="memory", key=f"{_IMU}/Gyroscope{item.upper()}/Sensor/Value")
        elif channel == "roll_pitch" and item in ("roll", "pitch"):
            col.update(source="memory", key=ROLL_KEY if item == "roll" else PITCH_KEY)
        elif channel == "gravity" and item in ("x", "y", "z"):
            col.update(source="gravity", axis="xyz".index(item))
        elif channel == "foot_contact" and item in FEET:
            col.update(source="contact", key=fsr_key(FEET[item]))
        elif channel == "phase" and item in ("sin", "cos"):
            col.update(source=f"phase_{item}")
        elif channel == "command" and item.isdigit():
            col.update(source="command", index=int(item))
        else:
            raise InputError(f"NAOqi export: observation {name!r} has no NAO source")
        out.append(col)
    return out


def _arrays(policy: ExportedPolicy) -> dict[str, np.ndarray]:
    """``policy.npz``'s arrays of ``policy``; a bad shape is one InputError line."""
    try:
        return policy_arrays(policy.spec, policy.params, policy.obs_mean, policy.obs_std)
    except ValueError as e:
        raise InputError(f"NAOqi export: {e}") from None


def _head(a: dict[str, np.ndarray]) -> dict[str, Any]:
    """Normaliser and action map of ``policy.npz``'s arrays ``a``."""
    return {"kind": str(a["kind"]), "obs_mean": a["obs_mean"], "obs_std": a["obs_std"],
            "clip_obs": float(a["clip_obs"]), "action_scale": a["action_scale"],
            "action_offset": a["action_offset"], "action_low": a["action_low"],
            "action_high": a["action_high"]}


def policy_layers(policy: ExportedPolicy) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """(normaliser and action map, generic layer list) of ``policy`` from the arrays of
    ``policy.npz`` (:func:`~evomotion.core.policies.export.policy_arrays`)."""
    return _layers(_arrays(policy))


def _layers(a: dict[str, np.ndarray]) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    if "n_layers" not in a:
        raise InputError(f"NAOqi export: a {a['kind']} policy has no layer list")
    n, tanh_last = int(a["n_layers"]), bool(a["output_tanh"])
    layers = [{"weight": a[f"layer{k}_weight"],
               "bias": a.get(f"layer{k}_bias"),
               "activation": "tanh" if k < n - 1 or tanh_last else "none"} for k in range(n)]
    return _head(a), layers


def structured_record(arrays: dict[str, np.ndarray], observation_names: Sequence[str]
                      ) -> dict[str, Any]:
    """The ``policy.json`` part of a structured policy (:mod:`evomotion.core.policies.structured`)
    from ``policy.npz``'s arrays: normaliser, action map, ``harmonics`` H, ``phase_columns``
    (which must be the observation's ``phase:sin``, ``phase:cos``: the runner's clock),
    ``command_columns`` (the raw command columns that modulate the tape),
    ``tape_coef[a][(1 + 2H)(1 + m)]``, ``feedback_gain[a][o - 2]`` and, with command feedback,
    ``command_gain[m][o - 2]``; a bad shape is one InputError line."""
    names = list(observation_names)
    o, act = len(names), int(np.shape(arrays["action_scale"])[0])
    h = int(arrays["harmonics"])
    cols = [int(c) for c in np.ravel(arrays["phase_columns"])]
    cmd = [int(c) for c in np.ravel(arrays.get("command_columns", np.zeros(0, np.int64)))]
    if any(not 0 <= c < o or not names[c].startswith("command:") for c in cmd):
        raise InputError(f"NAOqi export: the structured policy's command columns {cmd} must be "
                         "the observation's command columns")
    tape, gain = np.asarray(arrays["tape_coef"]), np.asarray(arrays["feedback_gain"])
    if len(cols) != 2 or [names[c] if 0 <= c < o else None for c in cols] != \
            ["phase:sin", "phase:cos"]:
        raise InputError(f"NAOqi export: the structured policy's phase columns {cols} must be "
                         "the observation's phase:sin and phase:cos (the runner's clock)")
    checks = [("tape_coef", tape, (act, (1 + 2 * h) * (1 + len(cmd)))),
              ("feedback_gain", gain, (act, o - 2))]
    extra = {}
    if "command_gain" in arrays:
        extra["command_gain"] = np.asarray(arrays["command_gain"])
        checks.append(("command_gain", extra["command_gain"], (len(cmd), o - 2)))
    for key, arr, shape in checks:
        if arr.shape != shape or not np.isfinite(arr).all():
            raise InputError(f"NAOqi export: the structured policy's {key} must be finite "
                             f"numbers of shape {shape}, got shape {arr.shape}")
    if int(np.shape(arrays["obs_mean"])[0]) != o:
        raise InputError(f"NAOqi export: {o} observation names for a normaliser of "
                         f"{np.shape(arrays['obs_mean'])[0]} columns")
    return {**_head(arrays), "harmonics": h, "phase_columns": cols, "command_columns": cmd,
            "tape_coef": tape, "feedback_gain": gain, **extra}


def policy_model(policy: ExportedPolicy, observation_names: Sequence[str]) -> dict[str, Any]:
    """The policy's part of ``policy.json``: its ``kind``, normaliser and action map, and the
    generic ``layers`` (linear, MLP) or the structured record (:func:`structured_record`)."""
    a = _arrays(policy)
    if str(a["kind"]) == "structured":
        return structured_record(a, observation_names)
    head, layers = _layers(a)
    return {**head, "layers": layers}


def naoqi_policy_record(policy: ExportedPolicy, observation_names: Sequence[str],
                        joints: Sequence[str], nominal_rad: Sequence[float],
                        lower_rad: Sequence[float], upper_rad: Sequence[float],
                        control_period_s: float, phase_period_s: float = 0.0,
                        nominal_pose: dict[str, float] | None = None,
                        contact_threshold_kg: float = CONTACT_THRESHOLD_KG,
                        command_ramp_s: float = 0.0,
                        capture_step: dict[str, Any] | None = None) -> dict[str, Any]:
    """The runner's ``policy.json`` record (see the module doc); one InputError line for a
    policy the NAO cannot run. ``capture_step``: the walk's capture-step record (run by
    :mod:`.naoqi_capture_step`, which reads the observations in :data:`CAPTURE_STEP_READS`)."""
    names, joints = list(observation_names), list(joints)
    if len(names) != policy.spec.obs_dim:
        raise InputError(f"NAOqi export: {len(names)} observation names for a policy of "
                         f"{policy.spec.obs_dim} inputs")
    if len(joints) != policy.spec.act_dim or not (len(nominal_rad) == len(lower_rad) ==
                                                  len(upper_rad) == len(joints)):
        raise InputError(f"NAOqi export: the policy sets {policy.spec.act_dim} joints; got "
                         f"{len(joints)} joints and {len(nominal_rad)}/{len(lower_rad)}/"
                         f"{len(upper_rad)} nominal/lower/upper angles")
    if "RHipYawPitch" in joints:
        raise InputError("NAOqi export: the policy drives RHipYawPitch; the NAO has one hip "
                         "yaw-pitch motor (LHipYawPitch)")
    if not 0.01 - 1e-9 <= float(control_period_s) <= 0.02 + 1e-9:
        raise InputError(f"NAOqi export: control period {control_period_s} s; the runner "
                         "sends targets every 10-20 ms")
    if float(phase_period_s) <= 0 and any(n.startswith("phase:") for n in names):
        raise InputError(f"NAOqi export: the policy reads phase; phase_period_s must be > 0, "
                         f"got {phase_period_s}")
    if capture_step:
        missing = [n for n in CAPTURE_STEP_READS if n not in names]
        if missing or "LHipYawPitch" not in joints:
            raise InputError("NAOqi export: the capture step reads "
                             f"{', '.join(missing) or 'LHipYawPitch among the joints'}, "
                             "which the policy does not")
    model = policy_model(policy, names)
    pose = dict(nominal_pose) if nominal_pose else dict(zip(joints, map(float, nominal_rad)))
    pose.pop("RHipYawPitch", None)
    used = sorted({n.split(":", 1)[0] for n in names} & set(APPROXIMATED))
    return {"format": FORMAT, **model,
            "observation": observation_sources(names),
            "approximated": {c: APPROXIMATED[c] for c in used},
            "roll_key": ROLL_KEY, "pitch_key": PITCH_KEY,
            "contact_threshold_kg": float(contact_threshold_kg),
            "phase_period_s": float(phase_period_s),
            "command_ramp_s": float(command_ramp_s),
            "control_period_s": float(control_period_s),
            "joints": joints, "nominal_rad": np.asarray(nominal_rad, float),
            "lower_rad": np.asarray(lower_rad, float), "upper_rad": np.asarray(upper_rad, float),
            "nominal_pose": pose,
            **({"capture_step": dict(capture_step)} if capture_step else {})}


def runner_source(name: str = RUNNER) -> str:
    """The text of :mod:`.policy_runner` (written out as ``policy_runner.py``), or with
    ``name`` :data:`CAPTURE_STEP` that of :mod:`.naoqi_capture_step`."""
    src = Path(__file__).with_name(_SOURCES[name])
    return decode_utf8(read_file_bytes(src, "NAOqi policy runner"), src)


def write_naoqi_policy(folder: str | Path, policy: ExportedPolicy,
                       observation_names: Sequence[str], joints: Sequence[str],
                       nominal_rad: Sequence[float], lower_rad: Sequence[float],
                       upper_rad: Sequence[float], control_period_s: float,
                       phase_period_s: float = 0.0,
                       nominal_pose: dict[str, float] | None = None,
                       command_ramp_s: float = 0.0,
                       capture_step: dict[str, Any] | None = None) -> dict[str, Path]:
    """``folder/policy_runner.py`` and ``folder/policy.json`` (made with its parent's
    permission, i.e. ``folder`` may be new), with ``capture_step`` also
    ``folder/capture_step.py``; everything is checked before anything is written."""
    record = naoqi_policy_record(policy, observation_names, joints, nominal_rad, lower_rad,
                                 upper_rad, control_period_s, phase_period_s, nominal_pose,
                                 command_ramp_s=command_ramp_s, capture_step=capture_step)
    folder = Path(folder)
    out = {"json": write_json(folder / POLICY_JSON, record, "NAOqi policy file", mkdir=True,
                              indent=1)}
    if capture_step:
        out["capture_step"] = atomic_write_text(folder / CAPTURE_STEP,
                                                runner_source(CAPTURE_STEP),
                                                "NAOqi capture step", mkdir=True)
    else:
        (folder / CAPTURE_STEP).unlink(missing_ok=True)  # an older export's
    out["runner"] = atomic_write_text(folder / RUNNER, runner_source(), "NAOqi policy runner",
                                      mkdir=True)
    return out


def approximations(observation_names: Sequence[str]) -> list[str]:
    """One note per channel the NAO approximates (``joint_vel``), for logs and reports."""
    used = sorted({n.split(":", 1)[0] for n in observation_names} & set(APPROXIMATED))
    return [f"{c}: {APPROXIMATED[c]}" for c in used]


__all__ = ["APPROXIMATED", "CAPTURE_STEP", "CAPTURE_STEP_READS", "CONTACT_THRESHOLD_KG", "FEET",
           "FORMAT", "UNMEASURED", "approximations", "fsr_key", "joint_key",
           "naoqi_policy_record", "observation_sources", "policy_layers", "policy_model",
           "runner_source", "structured_record", "write_naoqi_policy"]
