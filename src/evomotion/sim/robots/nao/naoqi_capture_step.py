# -*- coding: utf-8 -*-
# ruff: noqa: UP004, UP009, UP010, UP031
"""The walk controller's capture step for the NAOqi runner (written by evomotion as
``naoqi/capture_step.py`` beside ``policy_runner.py``, which loads it when ``policy.json``
has a ``capture_step`` record).

The standard library only (Python 2.7 or 3), one robot at a time: the same arithmetic as
evomotion's ``evomotion.studies.humanoid_omniwalk.capture_step`` (its docstring has the
equations): leg odometry ``v = -(w x p(q) + J(q) dq)`` from the NAO's closed-form leg
kinematics (paper 002, Graf et al. 2009), the velocity's offset from the command and from the
walk's own sway (learnt online), a dead band, and the swing foot's landing point moved by
``gain dv / w0`` through the walk engine's leg inverse kinematics (the engine's settings in
the record). On the NAO the joint velocities are the runner's finite differences of the
joint angles (the simulator's are the true ones): an approximation.
"""

from __future__ import division

import math

LEGS = {"left": ("LHipYawPitch", "LHipRoll", "LHipPitch", "LKneePitch", "LAnklePitch",
                 "LAnkleRoll"),
        "right": ("RHipYawPitch", "RHipRoll", "RHipPitch", "RKneePitch", "RAnklePitch",
                  "RAnkleRoll")}
#: the walk engine's settings the layer reads, with their accepted ranges
GAIT_KEYS = {"period_s": (0.05, 10.0), "swing_fraction": (0.05, 0.95),
             "step_height_m": (-1.0, 1.0), "leg_height_m": (-1.0, 1.0), "width_m": (-1.0, 1.0),
             "sway_m": (-1.0, 1.0), "sway_phase_rad": (-10.0, 10.0), "lean_rad": (-2.0, 2.0),
             "x_offset_m": (-1.0, 1.0)}
#: the observations the layer reads (the exporter checks a policy has them)
READS = tuple("joint_%s:%s" % (k, j) for k in ("pos", "vel") for s in ("left", "right")
              for j in LEGS[s][1:]) + ("gyro:x", "gyro:y", "gyro:z", "foot_contact:left",
                                       "foot_contact:right", "phase:sin", "phase:cos",
                                       "command:0", "command:1", "command:2")
#: the record's keys (the policy player names them for a record that lacks some)
KEYS = ("gain", "com_height_m", "deadband_mps", "reach_x_m", "out_y_m", "in_y_m",
        "calibration_rate", "calibration_gate_mps", "warmup_cycles", "bins", "gait",
        "geometry", "ranges")
EPS = 1e-4  # the odometry's directional-derivative step (rad per rad/s)


def _rx(a):
    c, s = math.cos(a), math.sin(a)
    return [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]


def _ry(a):
    c, s = math.cos(a), math.sin(a)
    return [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]


def _rz(a):
    c, s = math.cos(a), math.sin(a)
    return [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]


def _mm(*ms):
    out = ms[0]
    for b in ms[1:]:
        out = [[sum(out[i][k] * b[k][j] for k in range(3)) for j in range(3)]
               for i in range(3)]
    return out


def _mv(m, v):
    return [sum(m[i][k] * v[k] for k in range(3)) for i in range(3)]


def _t(m):
    return [[m[j][i] for j in range(3)] for i in range(3)]


def _clip(x, lo, hi):
    return min(max(x, lo), hi)


class Leg(object):
    """The NAO's closed-form leg kinematics (evomotion.sim.robots.nao.leg_ik) in metres."""

    def __init__(self, geometry):
        self.hip_y = float(geometry["hip_offset_y_m"])
        self.hip_z = float(geometry["hip_offset_z_m"])
        self.thigh = float(geometry["thigh_m"])
        self.tibia = float(geometry["tibia_m"])

    def hip(self, left):
        return [0.0, self.hip_y if left else -self.hip_y, -self.hip_z]

    def fk(self, q, left):
        """The ankle's position (torso frame) of the leg angles ``q[6]``."""
        s = 1.0 if left else -1.0
        r_hip = _mm(_rx(-s * math.pi / 4), _ry(q[0]), _rx(s * math.pi / 4), _rx(q[1]),
                    _ry(q[2]))
        h = self.hip(left)
        knee = [h[i] - self.thigh * r_hip[i][2] for i in range(3)]
        r_knee = _mm(r_hip, _ry(q[3]))
        return [knee[i] - self.tibia * r_knee[i][2] for i in range(3)]

    def ik(self, p, rot, left):
        """The six leg angles putting the ankle at ``p`` with the foot's rotation ``rot``."""
        s = 1.0 if left else -1.0
        h = self.hip(left)
        v = _mv(_t(rot), [h[i] - p[i] for i in range(3)])
        q5 = math.atan2(v[1], v[2])
        if q5 > math.pi / 2:
            q5 -= math.pi
        elif q5 <= -math.pi / 2:
            q5 += math.pi
        d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
        cos_knee = (d2 - self.thigh ** 2 - self.tibia ** 2) / (2 * self.thigh * self.tibia)
        q3 = math.acos(_clip(cos_knee, -1.0, 1.0))
        u = _mv(_rx(q5), v)
        q4 = math.atan2(-self.thigh * math.sin(q3), self.tibia + self.thigh * math.cos(q3)) \
            - math.atan2(u[0], u[2])
        q4 = (q4 + math.pi) % (2 * math.pi) - math.pi
        m = _mm(_rx(s * math.pi / 4), rot, _rx(-q5), _ry(-(q3 + q4)))
        b = math.atan2(s * math.hypot(m[1][0], m[1][2]), m[1][1])
        q0 = math.atan2(s * m[0][1], s * m[2][1])
        q2 = math.atan2(s * m[1][0], -s * m[1][2])
        return [q0, b - s * math.pi / 4, q2, q3, q4, q5]


def foot_phase(p, w):
    """``(u, lift)`` of a foot at its phase ``p`` (the engine's, evomotion's omni_gait)."""
    if p < w:
        s = p / w
        return -0.5 + 0.5 * (1.0 - math.cos(math.pi * s)), 0.5 * (1.0 - math.cos(2 * math.pi * s))
    return 0.5 - (p - w) / (1.0 - w), 0.0


class Engine(object):
    """The walk engine's leg angles for a phase, a command and the feet's offsets."""

    def __init__(self, gait, leg, ranges):
        self.g = dict((k, float(gait[k])) for k in GAIT_KEYS)
        self.leg = leg
        self.ranges = ranges  # joint -> (lo, hi)

    def legs(self, phase, command, offsets):
        """``{joint: angle}`` of both legs (clipped; RHipYawPitch = LHipYawPitch)."""
        g = self.g
        w, k = g["swing_fraction"], (1.0 - g["swing_fraction"]) * g["period_s"]
        dx, dy, dpsi = command[0] * k, command[1] * k, command[2] * k
        u_l, lift_l = foot_phase(phase % 1.0, w)
        u_r, lift_r = foot_phase((phase + 0.5) % 1.0, w)
        rel_yaw = (u_l - u_r) * dpsi
        sway = -g["sway_m"] * math.cos(2 * math.pi * (phase - 0.5 * w) + g["sway_phase_rad"])
        lean = _t(_ry(g["lean_rad"]))
        out = {}
        for f, (side, s, u, lift) in enumerate((("left", 1.0, u_l, lift_l),
                                                 ("right", -1.0, u_r, lift_r))):
            yaw = s * 0.5 * rel_yaw
            x = g["x_offset_m"] + u * dx + offsets[f][0]
            y = s * (self.leg.hip_y + g["width_m"]) + u * dy + sway + offsets[f][1]
            c, sn = math.cos(yaw), math.sin(yaw)
            pos = [c * x - sn * y, sn * x + c * y,
                   -(self.leg.hip_z + g["leg_height_m"]) + lift * g["step_height_m"]]
            q = self.leg.ik(_mv(lean, pos), _mm(lean, _rz(yaw)), s > 0)
            for name, a in zip(LEGS[side], q):
                out[name] = a
        out["RHipYawPitch"] = out["LHipYawPitch"]
        return dict((j, _clip(a, self.ranges[j][0], self.ranges[j][1]))
                    for j, a in out.items())


class CaptureStep(object):
    """``layer(obs, action) -> action`` with the feet moved (module doc); ``record`` is
    ``policy.json``'s ``capture_step``, ``names`` the observation's column names, ``joints``
    the action's joints, ``nominal`` their nominal angles."""

    def __init__(self, record, names, joints, nominal, control_period_s):
        check(record)
        self.gain = float(record["gain"])
        self.deadband = float(record["deadband_mps"])
        self.reach_x, self.out_y, self.in_y = (float(record[k]) for k in
                                               ("reach_x_m", "out_y_m", "in_y_m"))
        self.rate = float(record["calibration_rate"])
        self.gate = float(record["calibration_gate_mps"])
        self.warmup = int(record["warmup_cycles"])
        self.bins = int(record["bins"])
        self.omega = math.sqrt(9.81 / float(record["com_height_m"]))
        self.leg = Leg(record["geometry"])
        ranges = dict((j, (float(record["ranges"][j][0]), float(record["ranges"][j][1])))
                      for j in LEGS["left"] + LEGS["right"])
        self.engine = Engine(record["gait"], self.leg, ranges)
        self.w = float(record["gait"]["swing_fraction"])
        self.ahead = float(control_period_s) / float(record["gait"]["period_s"])
        self.dt = float(control_period_s)
        col = dict((n, i) for i, n in enumerate(names))
        missing = [n for n in READS if n not in col]
        if missing:
            raise ValueError("capture_step: it reads observation %r, which the policy does "
                             "not" % (missing[0],))
        legs5 = [LEGS[s][1:] for s in ("left", "right")]
        self.pos = [[col["joint_pos:" + j] for j in leg] for leg in legs5]
        self.vel = [[col["joint_vel:" + j] for j in leg] for leg in legs5]
        self.gyro = [col["gyro:" + a] for a in "xyz"]
        self.contact = [col["foot_contact:left"], col["foot_contact:right"]]
        self.phase_cols = col["phase:sin"], col["phase:cos"]
        self.command = [col["command:%d" % i] for i in range(3)]
        self.joints = list(joints)
        if "LHipYawPitch" not in self.joints or len(nominal) != len(self.joints):
            raise ValueError("capture_step: expected LHipYawPitch among the joints, with a "
                             "nominal angle each")
        self.hyp = self.joints.index("LHipYawPitch")
        self.hyp_nominal = float(nominal[self.hyp])
        self.sway = [[0.0, 0.0] for _ in range(self.bins)]
        self.steps = 0
        self.offset = [[0.0, 0.0], [0.0, 0.0]]
        self.lift_off = [[0.0, 0.0], [0.0, 0.0]]
        self.swinging = [False, False]
        self.hip_yaw_pitch, self.hip_yaw_pitch_rate = self.hyp_nominal, 0.0

    def velocity(self, obs, phase):
        """The torso's (vx, vy) by leg odometry, averaged over the feet in contact."""
        w = [obs[i] for i in self.gyro]
        est = []
        for f in range(2):
            q = [self.hip_yaw_pitch] + [obs[i] for i in self.pos[f]]
            dq = [self.hip_yaw_pitch_rate] + [obs[i] for i in self.vel[f]]
            p0 = self.leg.fk(q, f == 0)
            p1 = self.leg.fk([a + EPS * b for a, b in zip(q, dq)], f == 0)
            cross = [w[1] * p0[2] - w[2] * p0[1], w[2] * p0[0] - w[0] * p0[2],
                     w[0] * p0[1] - w[1] * p0[0]]
            est.append([-(cross[i] + (p1[i] - p0[i]) / EPS) for i in range(2)])
        touch = [obs[i] > 0.5 for i in self.contact]
        if not any(touch):
            touch = [phase % 1.0 >= self.w, (phase + 0.5) % 1.0 >= self.w]
        n = max(sum(1.0 for t in touch if t), 1.0)
        return [sum(est[f][i] for f in range(2) if touch[f]) / n for i in range(2)]

    def __call__(self, obs, action):
        phase = math.atan2(obs[self.phase_cols[0]], obs[self.phase_cols[1]]) \
            / (2 * math.pi) % 1.0
        command = [obs[i] for i in self.command]
        b = int(_round_even(phase * self.bins)) % self.bins
        sway = self.sway[b]
        v = self.velocity(obs, phase)
        dv = [v[i] - command[i] - sway[i] for i in range(2)]
        if not all(_finite(d) for d in dv):  # a NaN sensor moves no foot, learns no sway
            dv = [0.0, 0.0]
        self.steps += 1
        if math.hypot(dv[0], dv[1]) < self.gate:
            self.sway[b] = [sway[i] + self.rate * dv[i] for i in range(2)]
        if self.steps <= self.warmup * self.bins:
            dv = [0.0, 0.0]
        size = math.hypot(dv[0], dv[1])
        shrink = max(size - self.deadband, 0.0) / max(size, 1e-12)
        land = [self.gain * d * shrink / self.omega for d in dv]
        for f, side in ((0, 1.0), (1, -1.0)):
            p = (phase + 0.5 * f) % 1.0
            swing = p < self.w
            if swing and not self.swinging[f]:
                self.lift_off[f] = list(self.offset[f])
            if swing:
                goal = [_clip(land[0], -self.reach_x, self.reach_x),
                        side * _clip(side * land[1], -self.in_y, self.out_y)]
                a = 0.5 * (1.0 - math.cos(math.pi * _clip((p + self.ahead) / self.w, 0.0,
                                                          1.0)))
                lo = self.lift_off[f]
                self.offset[f] = [lo[i] + (goal[i] - lo[i]) * a for i in range(2)]
            self.swinging[f] = swing
        moved = self.engine.legs(phase, command, self.offset)
        plain = self.engine.legs(phase, command, [[0.0, 0.0], [0.0, 0.0]])
        out = [a + (moved[j] - plain[j] if j in moved else 0.0)
               for j, a in zip(self.joints, action)]
        hyp = self.hyp_nominal + out[self.hyp]
        if _finite(hyp):
            self.hip_yaw_pitch_rate = (hyp - self.hip_yaw_pitch) / self.dt
            self.hip_yaw_pitch = hyp
        else:  # a NaN action: the motor holds its last target
            self.hip_yaw_pitch_rate = 0.0
        return out


def _number(where, value, lo, hi):
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    if not ok or not (lo <= value <= hi):  # NaN fails too
        raise ValueError("capture_step: %s: expected a number in [%g, %g], got %r"
                         % (where, lo, hi, value))
    return float(value)


def check(record):
    """ValueError naming the first key of ``record`` out of its range."""
    if not isinstance(record, dict):
        raise ValueError("capture_step: expected an object, got %r" % (record,))
    for key, lo, hi in (("gain", 0.0, 10.0), ("com_height_m", 0.05, 2.0),
                        ("deadband_mps", 0.0, 10.0), ("reach_x_m", 0.0, 1.0),
                        ("out_y_m", 0.0, 1.0), ("in_y_m", 0.0, 1.0),
                        ("calibration_rate", 0.0, 1.0), ("calibration_gate_mps", 0.0, 10.0),
                        ("warmup_cycles", 0, 1000), ("bins", 1, 10000)):
        _number(key, record.get(key), lo, hi)
    gait, geometry = record.get("gait"), record.get("geometry")
    if not isinstance(gait, dict) or not isinstance(geometry, dict):
        raise ValueError("capture_step: gait and geometry: expected objects")
    for key, (lo, hi) in GAIT_KEYS.items():
        _number("gait." + key, gait.get(key), lo, hi)
    for key in ("hip_offset_y_m", "hip_offset_z_m", "thigh_m", "tibia_m"):
        _number("geometry." + key, geometry.get(key), 0.001, 2.0)
    ranges = record.get("ranges")
    for j in LEGS["left"] + LEGS["right"]:
        r = ranges.get(j) if isinstance(ranges, dict) else None
        if not isinstance(r, list) or len(r) != 2:
            raise ValueError("capture_step: ranges.%s: expected [low, high]" % j)
        _number("ranges.%s" % j, r[1], _number("ranges.%s" % j, r[0], -7.0, 7.0), 7.0)


def _finite(x):
    return not (math.isnan(x) or math.isinf(x))


def _round_even(x):
    """numpy's rounding (halves to even)."""
    r = math.floor(x + 0.5)
    if r - x == 0.5 and r % 2 != 0:
        r -= 1
    return r
