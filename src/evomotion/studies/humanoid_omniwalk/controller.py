"""The walk controller: which joints it drives, what it reads, where its search starts.

The NAO (``robot`` "nao", the default):

- Drives 15 joints every control period: both legs (the hip yaw-pitch motor once, as on the
  real NAO, where ``RHipYawPitch`` follows ``LHipYawPitch``) and both shoulders' pitch and
  roll; targets are offsets from the engine's mean standing-in-place pose, clipped to the
  joint ranges (:mod:`evomotion.sim.closed_loop`).
- Reads the 10 leg servos' angles and velocities, the IMU (gravity direction, gyro), both
  feet's contacts, the gait clock (``sin``/``cos`` of ``2π t / period_s``) and the command.
- Is a structured policy (:mod:`evomotion.core.policies.structured`): a tape of ``H``
  harmonics, each an affine function of the command, plus linear feedback on the normalised
  observation. :meth:`Controller.initial_params` fits the tape by least squares to the walk
  engine (:mod:`.omni_gait`) over a grid of commands, one cycle each (feedback 0).

Any other biped (the OP3, the dm_control humanoid, a spec ``.toml``): the same structure and
observations on its own legs: it drives the joints of both leg chains (from the pelvis to each
foot; :class:`evomotion.sim.leg_ik.LegChain`), reads its evolved joints (the spec's
``[evolve]``), and its tape is fitted to the engine placed around its ready pose by numerical
leg IK, scaled to its leg (:mod:`.ik_gait`). Its motors' speeds are checked only where the robot
declares them (the ``speed_limits`` capability); otherwise the speed excess is 0.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from evomotion.core.policies import StructuredSpec, fit_tape
from evomotion.core.policies.mirror import (
    MirrorBasis,
    SignedPermutation,
    structured_mirror,
)
from evomotion.sim.closed_loop import ClosedLoopResult, ClosedLoopSimulator
from evomotion.sim.control_period import whole_steps
from evomotion.sim.observations import ObservationSpec, observation_mirror
from evomotion.sim.robots import load_robot, nao
from evomotion.sim.robots.nao.joint_limits import SPEED_LIMITS
from evomotion.sim.rollout import ServoWork
from evomotion.studies.humanoid_omniwalk.capture_step import CaptureStep, com_height
from evomotion.studies.humanoid_omniwalk.ik_gait import IKGait
from evomotion.studies.humanoid_omniwalk.omni_gait import OmniGait, targets

ARMS = ("LShoulderPitch", "RShoulderPitch", "LShoulderRoll", "RShoulderRoll")
DRIVEN = (*nao.LEFT_LEG, *nao.RIGHT_LEG[1:], *ARMS)
CHANNELS = ("joint_pos", "joint_vel", "gravity", "gyro", "foot_contact", "phase", "command")
#: the commands the tape is fitted over: vx (m/s) x vy (m/s) x ω (rad/s)
FIT_GRID = (np.linspace(-0.2, 0.45, 6), np.linspace(-0.2, 0.2, 5), np.linspace(-1.2, 1.2, 5))
FIT_DT_S = 0.01


@dataclass(frozen=True)
class Mirror:
    """A symmetric controller's parameters ``basis.expand(z)`` and the observation's mirror
    (:mod:`evomotion.core.policies.mirror`)."""

    basis: MirrorBasis
    observation: SignedPermutation


class Controller:
    """The controller's simulator, policy spec and start (see the module doc)."""

    def __init__(self, gait: OmniGait, control_period_s: float = 0.02, harmonics: int = 3,
                 clip_obs: float = 5.0, threads: int = 1,
                 command_feedback: bool = False, feedback_start: float = 0.0,
                 robot: str = "nao", symmetric: bool = False,
                 capture_gain: float = 0.0) -> None:
        from evomotion.errors import InputError

        self.feedback_start = float(feedback_start)
        self.robot = r = load_robot(robot or "nao")
        self.dt = float(r.model.opt.timestep)
        k = whole_steps(control_period_s, self.dt)
        if k is None:
            raise InputError(f"problem.control_period_s: {control_period_s} s is not a whole "
                             f"number of {r.name}'s {self.dt} s physics steps")
        self.control_dt = k * self.dt
        #: the NAO (its closed-form leg IK: the bundled spec's capability; a copy of nao.toml
        #: elsewhere has none and is walked as any biped): the closed-form engine, the
        #: shoulders, one hip yaw-pitch motor
        self.closed_form = r.has("leg_ik")
        if self.closed_form:
            self.gait = gait
            self.engine = lambda phase, command: targets(gait, phase, command)
            col = {j: i for i, j in enumerate(nao.JOINTS)}
            self.driven = DRIVEN
            self.columns = np.array([col[j] for j in DRIVEN])
            self.followers = {"RHipYawPitch": "LHipYawPitch"}
            speeds = SPEED_LIMITS
        else:
            ik = IKGait(r, gait)
            self.gait, self.engine, self.columns = ik.gait, ik.targets, ik.columns
            self.driven = tuple(r.joints[c] for c in self.columns)
            self.followers = {}
            speeds = (r.capability("speed_limits", "humanoid-walk").SPEED_LIMITS
                      if r.has("speed_limits") else {})
        phases = np.linspace(0.0, 1.0, 48, endpoint=False)
        self.nominal = self.engine(phases, np.zeros((48, 3))).mean(axis=0)
        self.obs_spec = ObservationSpec(CHANNELS, phase_period_s=self.gait.period_s,
                                        command_size=3)
        self.steps_per_control = k
        self.sim = self.simulator(self.obs_spec, threads)
        names = list(self.sim.observe.names)
        self.policy = StructuredSpec(
            self.sim.observation_size, self.columns.size,
            phase_columns=(names.index("phase:sin"), names.index("phase:cos")),
            harmonics=harmonics, clip_obs=clip_obs,
            command_columns=tuple(names.index(f"command:{i}") for i in range(3)),
            command_feedback=command_feedback,
            low=self.sim.lower - self.nominal[self.columns],
            high=self.sim.upper - self.nominal[self.columns])
        #: a mirror-symmetric controller's parameters (problem.symmetric) or None
        self.mirror = self._mirror() if symmetric else None
        self.window = max(1, int(round(self.gait.period_s / self.control_dt)))  # one cycle
        self.state0 = r.state_at(self.nominal)  # the NAO's own rule, bit for bit (build.py)
        self.speed_limits = np.array([speeds.get(j, np.inf) for j in self.driven])
        self.work = ServoWork(r.model, self.columns)
        #: the capture step's gain (:mod:`.capture_step`; 0: none)
        self.capture_gain = float(capture_gain)
        if self.capture_gain and not self.closed_form:
            raise InputError(f"problem.capture_gain: the capture step needs the NAO's leg "
                             f"kinematics; robot {r.name!r} has none (set it to 0)")

    def simulator(self, spec: ObservationSpec, threads: int) -> ClosedLoopSimulator:
        """A closed-loop simulator of this controller's robot, joints, followers, nominal
        pose and control period reading ``spec`` (``self.sim`` reads :data:`CHANNELS`;
        benchmarks and tests read more, e.g. the torso's true velocity)."""
        r = self.robot
        return ClosedLoopSimulator(r, spec, self.steps_per_control, threads,
                                   columns=self.columns, nominal=self.nominal,
                                   followers=[(r.joints.index(f), r.joints.index(lead))
                                              for f, lead in self.followers.items()])

    @cached_property
    def com_height_m(self) -> float:
        """The CoM's height (m) in the standing pose ``state0`` (the capture step's ω₀)."""
        return com_height(self.robot, self.state0)

    def _mirror(self) -> Mirror:
        """The robot's left-right mirror on the driven joints (a follower is its leader) and
        on the observation (the walk's command ``(vx, vy, ω)`` -> ``(vx, -vy, -ω)``)."""
        from evomotion.errors import InputError

        if not self.robot.has("mirror"):
            raise InputError(f"problem.symmetric: robot {self.robot.name!r} declares no "
                             "left-right mirror of its joints (the NAO does)")
        joint_mirror = self.robot.capability("mirror", "humanoid-walk").joint_mirror
        names = list(self.driven)
        pairs = [joint_mirror(j) for j in names]
        action = SignedPermutation(
            np.array([names.index(self.followers.get(p, p)) for p, _ in pairs]),
            np.array([s for _, s in pairs]))
        obs = SignedPermutation(*observation_mirror(self.sim.observe.names, joint_mirror,
                                                    (1.0, -1.0, -1.0)))
        return Mirror(MirrorBasis.of(structured_mirror(self.policy, action, obs)), obs)

    def initial_params(self) -> np.ndarray:
        return self._fitted.copy()

    @cached_property
    def _fitted(self) -> np.ndarray:
        grid = np.stack(np.meshgrid(*FIT_GRID, indexing="ij"), axis=-1).reshape(-1, 3)
        t = np.arange(0.0, self.gait.period_s, FIT_DT_S)
        tt, cc = np.tile(t, len(grid)), np.repeat(grid, t.size, axis=0)
        q = self.engine(tt / self.gait.period_s, cc)[:, self.columns]
        coeffs = fit_tape(tt, q - self.nominal[self.columns], self.gait.period_s,
                          self.policy.harmonics, commands=cc)
        params = self.policy.params_from_tape(coeffs)
        if self.policy.command_feedback and self.feedback_start:
            # the step adjustment's start: vx follows the forward lean (gravity:x)
            layers = self.policy.unflatten(params)
            fed = [self.sim.observe.names[k] for k in self.policy.feedback_columns]
            G = layers[2][0].copy()
            G[0, fed.index("gravity:x")] = self.feedback_start
            params = self.policy.flatten([layers[0], layers[1], (G, None)])
        return params

    def run(self, params: np.ndarray, mean: np.ndarray, std: np.ndarray, worlds: list,
            nstep: int, commands: np.ndarray) -> ClosedLoopResult:
        """Episode ``i``: ``params[i]`` with its normaliser in ``worlds[i]`` under
        ``commands[i]`` (``[n, C, 3]``), from the engine's standing pose (with the capture
        step on top where ``capture_gain``)."""
        spec = self.policy
        layer = (CaptureStep(self, list(self.sim.observe.names), len(params),
                             self.capture_gain)
                 if self.capture_gain else None)

        def policy(rows: np.ndarray, obs: np.ndarray) -> np.ndarray:
            act = spec.act(params[rows], obs, mean[rows], std[rows])
            return act if layer is None else layer(rows, obs, act)

        return self.sim.run(policy, worlds, nstep, commands=commands,
                            initial_state=self.state0, record_states=True,
                            record_targets=True)

    def effort(self, res: ClosedLoopResult) -> tuple[np.ndarray, np.ndarray]:
        """(mean servo power W, mean speed excess) per episode while up (module doc of
        :mod:`.problem`); the power sampled at the control steps."""
        assert res.targets is not None
        done = np.maximum(np.ceil(res.steps / self.sim.k).astype(np.int64), 1)
        n, C, _ = res.targets.shape
        if res.states is not None:
            ctrl = self.sim.full_targets(res.targets)
            work = self.work(res.states[:, :C], ctrl, done - 1) * self.sim.k
            power = work / (done * self.control_dt)
        else:
            power = np.zeros(n)
        rate = np.abs(np.diff(res.targets, axis=1)) / self.control_dt
        over = np.maximum(rate / self.speed_limits - 1.0, 0.0).sum(axis=2)
        valid = np.arange(C - 1)[None] < (done[:, None] - 1)
        excess = (over * valid).sum(axis=1) / np.maximum(done - 1, 1)
        return power, excess
