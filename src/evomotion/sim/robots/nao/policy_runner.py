#!/usr/bin/env python
# -*- coding: utf-8 -*-
# ruff: noqa: UP004, UP009, UP010, UP024, UP025, UP031, UP032, SIM108
"""Run an evomotion closed-loop policy on a real NAO through NAOqi (written by evomotion).

    python policy_runner.py [policy.json] [--ip 127.0.0.1] [--port 9559] [--seconds 10]
                            [--period-ms 20] [--command vx,vy,w] [--command-key KEY]
                            [--dry-run]

One file (two with a capture step), the standard library only (no numpy, no evomotion): it
runs under NAOqi 2.8's own Python 2.7 on the robot and under Python 3 with the ``naoqi`` SDK
module on a PC. Every control
period it reads the sensors with ONE ``ALMemory.getListData(keys)`` call, builds the
observation as evomotion's simulator does (``policy.json`` lists each column's source), runs
the policy (normalise, clip, layers with tanh or a structured policy's phase tape plus
linear feedback, ``offset + scale * y``, clip), with a ``capture_step`` record in
``policy.json`` moves the swing foot by the capture point (``capture_step.py`` beside this
file, loaded then; the same period required) and sends
``clip(nominal + action, lower, upper)`` to the joints through a DCM "timed commands" alias
(``setAlias``, time ``dcm.getTime(delay_ms)``).

Sources per observation column: ``memory`` (an ALMemory value as it is: joint angles, gyro,
AngleX/AngleY), ``diff`` (joint velocity: the NAO has no velocity sensor, so the change of the
position over the measured period; 0 on the first step), ``gravity`` (``R^T (0, 0, -1)`` from
AngleX = roll, AngleY = pitch, ZYX convention: ``(sin p, -sin r cos p, -cos r cos p)``),
``contact`` (1 when a foot's FSR total weight in kg is above ``contact_threshold_kg``, else
0), ``phase_sin``/``phase_cos`` (the runner's own clock from the loop's start), ``command``
(``--command``, fixed; or ``--command-key KEY``: the list of numbers a behaviour puts at that
ALMemory key with ``insertData``, read in the same ``getListData`` call every step, the last
good one kept while the key holds anything else). With ``command_ramp_s`` in ``policy.json``
(a walk controller's) the command the policy sees moves linearly from its value to each new
one over that time, from zero at the start, as in training.

Before the loop: the stiffness of the driven joints is set to 1 and the robot goes to the
nominal pose (ALMotion); ``--dry-run`` sends nothing and prints the targets. Ctrl-C ends the
loop holding the last targets: the stiffness is NOT released, a standing NAO without
stiffness falls (use Choregraphe or ``ALMotion.rest()`` to sit it down).
"""

from __future__ import division, print_function

import argparse
import json
import math
import os
import sys
import time

FORMAT = "evomotion-naoqi-policy/1"
ALIAS = "evomotion_policy_targets"
_now = getattr(time, "monotonic", time.time)  # Python 2.7 has no time.monotonic


def _finite(x):
    return not (math.isinf(x) or math.isnan(x))


def _bound(values, default):
    """JSON numbers with ``null`` for "no bound" (``default``: -inf or +inf)."""
    return [default if v is None else float(v) for v in values]


def _sum_products(weights, values):
    """``w0 v0 + w1 v1 + ...`` summed left to right (evomotion's ``_row_dot`` order)."""
    total = weights[0] * values[0]
    for w, v in zip(weights[1:], values[1:]):
        total = total + w * v
    return total


def _matrix(record, key, rows, cols):
    """``record[key]`` as ``rows`` lists of ``cols`` floats; a bad shape is one ValueError."""
    m = [[float(v) for v in row] for row in record[key]]
    if len(m) != rows or any(len(row) != cols for row in m):
        raise ValueError("policy.json: %s must be %d x %d numbers" % (key, rows, cols))
    return m


class Policy(object):
    """``policy(obs) -> action``: normalise, clip, then the layers (tanh between, and after the
    last with ``output_tanh``) or the structured tape plus feedback, ``offset + scale * y``,
    clipped to ``[low, high]``."""

    def __init__(self, record):
        self.kind = str(record.get("kind", "layers"))
        if self.kind not in ("layers", "linear", "mlp", "structured"):
            raise ValueError("policy.json: a %r policy; this runner runs linear, mlp and "
                             "structured ones" % (self.kind,))
        self.mean = [float(v) for v in record["obs_mean"]]
        self.std = [float(v) for v in record["obs_std"]]
        clip = record.get("clip_obs")
        self.clip_obs = None if clip is None else float(clip)
        self.scale = [float(v) for v in record["action_scale"]]
        self.offset = [float(v) for v in record["action_offset"]]
        self.low = _bound(record["action_low"], -float("inf"))
        self.high = _bound(record["action_high"], float("inf"))
        self.layers = []
        if self.kind == "structured":
            self._init_structured(record)
            return
        for layer in record["layers"]:
            W = [[float(v) for v in row] for row in layer["weight"]]
            b = layer.get("bias")
            self.layers.append((W, None if b is None else [float(v) for v in b],
                                layer["activation"]))

    def _init_structured(self, record):
        """The tape ``tape_coef[a][1 + 2H]``, gains ``feedback_gain[a][o - 2]`` and the raw
        phase columns (sin, cos), checked against the normaliser and action map."""
        o, a = len(self.mean), len(self.scale)
        self.harmonics = int(record["harmonics"])
        cols = [int(c) for c in record["phase_columns"]]
        if self.harmonics < 0 or len(cols) != 2 or cols[0] == cols[1] or \
                not all(0 <= c < o for c in cols):
            raise ValueError("policy.json: harmonics %r, phase_columns %r for %d observations"
                             % (record["harmonics"], record["phase_columns"], o))
        self.phase_columns = cols
        self.command_columns = [int(c) for c in record.get("command_columns", [])]
        if not all(0 <= c < o and c not in cols for c in self.command_columns):
            raise ValueError("policy.json: command_columns %r for %d observations"
                             % (record["command_columns"], o))
        self.keep = [m for m in range(o) if m not in cols]
        self.tape = _matrix(record, "tape_coef", a, (1 + 2 * self.harmonics)
                            * (1 + len(self.command_columns)))
        self.gain = _matrix(record, "feedback_gain", a, o - 2)
        # command feedback: the tape reads c + G x (absent: the plain command)
        self.command_gain = _matrix(record, "command_gain", len(self.command_columns), o - 2) \
            if "command_gain" in record else None

    def structured(self, obs, h):
        """``tape(phi) + K x`` of the raw ``obs`` and normalised ``h``: ``1, sin phi, cos phi,
        ..., sin H phi, cos H phi`` from the raw phase columns by angle addition (then each raw
        command value times them, with ``command_columns``), as
        evomotion's ``structured.py`` and ``policy.py`` compute them."""
        i, j = self.phase_columns
        s1, c1 = obs[i], obs[j]
        features = [1.0]
        s, c = s1, c1
        for k in range(1, self.harmonics + 1):
            features += [s, c]
            if k < self.harmonics:
                s, c = s * c1 + c * s1, c * c1 - s * s1
        base = list(features)
        x = [h[m] for m in self.keep]
        for k, m in enumerate(self.command_columns):  # a command-modulated tape: (f, c_1 f, ...)
            cm = obs[m]
            if self.command_gain is not None and x:
                cm = cm + _sum_products(self.command_gain[k], x)
            features += [cm * f for f in base]
        y = []
        for tape, gain in zip(self.tape, self.gain):
            t = _sum_products(tape, features)
            y.append(t + _sum_products(gain, x) if x else t)
        return y

    def __call__(self, obs):
        h = [(x - m) / s for x, m, s in zip(obs, self.mean, self.std)]
        if self.clip_obs is not None:
            c = self.clip_obs
            h = [min(max(v, -c), c) for v in h]
        if self.kind == "structured":
            h = self.structured([float(v) for v in obs], h)
        for W, b, activation in self.layers:
            out = [math.fsum(w * v for w, v in zip(row, h)) for row in W]
            if b is not None:
                out = [o + bi for o, bi in zip(out, b)]
            if activation == "tanh":
                out = [math.tanh(o) for o in out]
            elif activation != "none":
                raise ValueError("unknown activation %r" % (activation,))
            h = out
        return [min(max(o + s * y, lo), hi) for o, s, y, lo, hi
                in zip(self.offset, self.scale, h, self.low, self.high)]


class Observer(object):
    """Builds the observation from one ``getListData`` answer (see the module doc)."""

    def __init__(self, record, command=None, command_key=None):
        self.columns = record["observation"]
        self.roll_key, self.pitch_key = record["roll_key"], record["pitch_key"]
        self.threshold = float(record["contact_threshold_kg"])
        self.phase_period = float(record.get("phase_period_s") or 0.0)
        self.command = list(command or [])
        self.command_key = command_key
        self.ramp = CommandRamp(float(record.get("command_ramp_s") or 0.0))
        if self.phase_period <= 0 and any(c["source"] in ("phase_sin", "phase_cos")
                                          for c in self.columns):
            raise ValueError("policy.json: the policy reads phase; phase_period_s must be > 0")
        keys = []
        for col in self.columns:
            if col["source"] in ("memory", "diff", "contact") and str(col["key"]) not in keys:
                keys.append(str(col["key"]))
        if any(c["source"] == "gravity" for c in self.columns):
            for k in (str(self.roll_key), str(self.pitch_key)):
                if k not in keys:
                    keys.append(k)
        need = 1 + max([int(c["index"]) for c in self.columns if c["source"] == "command"]
                       or [-1])
        if command_key is not None:
            keys.append(str(command_key))
            self.command = [0.0] * need if len(self.command) < need else self.command
        self.keys = keys
        self.index = dict((k, i) for i, k in enumerate(keys))
        if len(self.command) < need:
            raise ValueError("the policy reads %d command values: give --command or "
                             "--command-key" % need)
        self.last = None  # (time s, positions by key) of the previous step

    def __call__(self, values, t):
        """The observation of sensor ``values`` (in :attr:`keys` order) at time ``t`` (s)."""
        values = list(values)
        if self.command_key is not None:
            self.command = _command(values.pop(), self.command)
            values.append(0.0)
        v = [float(x) for x in values]
        if len(v) != len(self.keys):
            raise ValueError("ALMemory returned %d values for %d keys" % (len(v), len(self.keys)))
        prev = self.last
        dt = None if prev is None else t - prev[0]
        g = cmd = None
        obs = []
        for col in self.columns:
            src = col["source"]
            if src == "memory":
                obs.append(v[self.index[col["key"]]])
            elif src == "diff":
                i = self.index[col["key"]]
                obs.append(0.0 if prev is None or dt <= 0 else (v[i] - prev[1][i]) / dt)
            elif src == "contact":
                obs.append(1.0 if v[self.index[col["key"]]] > self.threshold else 0.0)
            elif src == "gravity":
                if g is None:
                    g = gravity(v[self.index[self.roll_key]], v[self.index[self.pitch_key]])
                obs.append(g[int(col["axis"])])
            elif src in ("phase_sin", "phase_cos"):
                angle = 2.0 * math.pi * t / self.phase_period
                obs.append(math.sin(angle) if src == "phase_sin" else math.cos(angle))
            elif src == "command":
                if cmd is None:
                    cmd = self.ramp(self.command, t)
                obs.append(float(cmd[int(col["index"])]))
            else:
                raise ValueError("unknown observation source %r" % (src,))
        self.last = (t, v)
        return obs


def _command(value, last):
    """The numbers at the command key, or ``last`` while it holds anything else."""
    try:
        new = [float(x) for x in value]
    except (TypeError, ValueError):
        return last
    if len(new) < len(last) or not all(_finite(x) for x in new):
        return last
    return new[:len(last)]


class CommandRamp(object):
    """The command moved linearly to each new target over ``ramp_s`` (0: at once), from
    zero at the first call."""

    def __init__(self, ramp_s):
        self.ramp_s = float(ramp_s)
        self.start = self.target = None
        self.t_start = 0.0

    def __call__(self, target, t):
        target = [float(x) for x in target]
        if self.target is None:
            self.start, self.target, self.t_start = [0.0] * len(target), target, t
        elif target != self.target:
            self.start, self.target, self.t_start = self.value(t), target, t
        return self.value(t)

    def value(self, t):
        if self.ramp_s <= 0:
            return list(self.target)
        f = min(max((t - self.t_start) / self.ramp_s, 0.0), 1.0)
        return [a + (b - a) * f for a, b in zip(self.start, self.target)]


def gravity(roll, pitch):
    """``R^T (0, 0, -1)`` for ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (yaw drops out)."""
    cp = math.cos(pitch)
    return [math.sin(pitch), -math.sin(roll) * cp, -math.cos(roll) * cp]


class Runner(object):
    """One control loop: ``memory`` (ALMemory), ``dcm`` (DCM), ``motion`` (ALMotion) proxies,
    ``clock()`` in seconds, ``sleep(s)``; :meth:`step` is one control period."""

    def __init__(self, record, memory, dcm, motion, command=None, clock=_now,
                 sleep=time.sleep, dry_run=False, delay_ms=0, command_key=None):
        if record.get("format") != FORMAT:
            raise ValueError("policy.json: format %r, this runner reads %r"
                             % (record.get("format"), FORMAT))
        self.record = record
        self.policy = Policy(record)
        self.observe = Observer(record, command, command_key)
        self.joints = [str(j) for j in record["joints"]]
        self.nominal = [float(v) for v in record["nominal_rad"]]
        self.lower = _bound(record["lower_rad"], -float("inf"))
        self.upper = _bound(record["upper_rad"], float("inf"))
        self.memory, self.dcm, self.motion = memory, dcm, motion
        self.clock, self.sleep = clock, sleep
        self.dry_run, self.delay_ms = dry_run, int(delay_ms)
        self.t0 = None
        self.last_targets = None
        self.layer = None
        if record.get("capture_step") is not None:  # {} or 0: one ValueError line
            self.layer = _capture_step_module().CaptureStep(
                record["capture_step"], [str(c["name"]) for c in record["observation"]],
                self.joints, self.nominal, float(record["control_period_s"]))

    def start(self, pose_speed=0.1):
        """Stiffness on, the nominal pose, the DCM alias (nothing sent with ``dry_run``)."""
        if not self.dry_run:
            pose = self.record["nominal_pose"]
            names = [str(n) for n in pose]
            self.motion.setStiffnesses(names, 1.0)
            self.motion.angleInterpolationWithSpeed(names, [float(pose[n]) for n in pose],
                                                    float(pose_speed))
            keys = ["Device/SubDeviceList/%s/Position/Actuator/Value" % j for j in self.joints]
            self.dcm.createAlias([ALIAS, keys])
        self.t0 = self.clock()

    def step(self):
        """Read the sensors, run the policy, send (and return) the joint targets."""
        values = self.memory.getListData(self.observe.keys)
        obs = self.observe(values, self.clock() - self.t0)
        action = self.policy(obs)
        if self.layer is not None:
            action = self.layer(obs, action)
        targets = [min(max(n + (0.0 if math.isnan(a) else a), lo), hi) for n, a, lo, hi
                   in zip(self.nominal, action, self.lower, self.upper)]
        if not self.dry_run:
            when = self.dcm.getTime(self.delay_ms)
            self.dcm.setAlias([ALIAS, "ClearAll", "time-separate", 0, [when],
                               [[t] for t in targets]])
        self.last_targets = targets
        return targets

    def run(self, seconds, period_s, on_step=None):
        """``step`` every ``period_s`` for ``seconds`` (Ctrl-C: stop, holding the last
        targets); the number of steps and of late ones."""
        steps = late = 0
        deadline = self.clock()
        try:
            while steps * period_s < seconds:
                targets = self.step()
                steps += 1
                if on_step is not None:
                    on_step(targets)
                deadline += period_s
                wait = deadline - self.clock()
                if wait > 0:
                    self.sleep(wait)
                else:
                    late += 1
                    deadline = self.clock()
        except KeyboardInterrupt:
            print("stopped: holding the last targets, stiffness on", file=sys.stderr)
        return steps, late


def _capture_step_module():
    """``capture_step.py`` beside this file (Python 3's importlib, Python 2.7's imp)."""
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "capture_step.py")
    if not os.path.isfile(path):
        raise IOError("policy.json has a capture step; %s is missing" % path)
    try:
        import importlib.util
    except ImportError:  # Python 2.7
        import imp
        return imp.load_source("evomotion_capture_step", path)
    spec = importlib.util.spec_from_file_location("evomotion_capture_step", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def load(path):
    with open(path) as fh:
        return json.load(fh)


def main(argv=None):
    here = os.path.dirname(os.path.abspath(__file__))
    p = argparse.ArgumentParser(description="Run an evomotion policy on a NAO (NAOqi DCM).")
    p.add_argument("policy", nargs="?", default=os.path.join(here, "policy.json"))
    p.add_argument("--ip", default="127.0.0.1")
    p.add_argument("--port", type=int, default=9559)
    p.add_argument("--seconds", type=float, default=10.0)
    p.add_argument("--period-ms", type=float, default=None,
                   help="control period (10-20 ms; default the policy's)")
    p.add_argument("--command", default="", help="vx,vy,w: the command channel's values")
    p.add_argument("--command-key", default=None,
                   help="an ALMemory key holding [vx, vy, w], read every step")
    p.add_argument("--dry-run", action="store_true", help="print targets, send nothing")
    args = p.parse_args(argv)
    try:
        record = load(args.policy)
        period = (args.period_ms / 1000.0 if args.period_ms is not None
                  else float(record["control_period_s"]))
        if not 0.01 <= period <= 0.02 + 1e-9 or not args.seconds > 0:
            raise ValueError("--period-ms must be 10 to 20 and --seconds > 0")
        own = float(record["control_period_s"])
        if record.get("capture_step") is not None and abs(period - own) > 1e-9:
            raise ValueError("--period-ms: the capture step runs at the policy's period, "
                             "%g ms" % (own * 1000.0))
        command = [float(x) for x in args.command.split(",") if x.strip()]
        from naoqi import ALProxy
        memory = ALProxy("ALMemory", args.ip, args.port)
        dcm = ALProxy("DCM", args.ip, args.port)
        motion = ALProxy("ALMotion", args.ip, args.port)
        runner = Runner(record, memory, dcm, motion, command, dry_run=args.dry_run,
                        command_key=args.command_key)
        runner.start()
        show = (lambda t: print(",".join(repr(x) for x in t))) if args.dry_run else None
        steps, late = runner.run(args.seconds, period, show)
    except (IOError, OSError, ValueError, KeyError, ImportError, RuntimeError) as e:
        print("error: %s" % (e,), file=sys.stderr)
        return 1
    print("%d control steps of %.1f ms, %d late" % (steps, period * 1000.0, late),
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
