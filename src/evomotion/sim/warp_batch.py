"""One device batch of the Warp closed loop (:mod:`evomotion.sim.warp_closed_loop`): MuJoCo
Warp model and data of ``nworld`` worlds, the loop's buffers, the host round trips (upload a
population's carried state, download it with the recorded steps) and the captured phases.

Rows ``m .. nworld - 1`` of a batch of ``m`` running individuals repeat the last one and are
``done`` from the start: stepped, never recorded, their results dropped.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from evomotion.errors import InputError
from evomotion.sim import warp_closed_loop_kernels as kern
from evomotion.sim.observations import observed_actuators
from evomotion.sim.warp_memory import estimate_bytes
from evomotion.sim.warp_policy import DeviceLayers


@dataclass(frozen=True)
class Layout:
    """What a run's buffers depend on (batches are kept for runs of the same layout)."""

    nctrl: int
    depth: int  # the latency ring's control steps
    record_states: bool
    record_targets: bool
    fields: tuple[str, ...]  # batched model fields (perturbed worlds)
    pushed: bool
    spec: Any  # the device policy's spec, None: the host's

    def key(self) -> tuple:
        return (self.nctrl, self.depth, self.record_states, self.record_targets, self.fields,
                self.pushed, id(self.spec))


def column_table(observe, robot) -> tuple[np.ndarray, np.ndarray]:
    """``(kind[o], index[o])`` of every observation column for the ``observe`` kernel."""
    m = robot.model
    free_q, free_v = int(m.jnt_qposadr[0]), int(m.jnt_dofadr[0])
    joints = m.actuator_trnid[observed_actuators(robot, observe.spec.joints), 0]
    table = {
        "joint_pos": [(kern.QPOS, int(a)) for a in m.jnt_qposadr[joints]],
        "joint_vel": [(kern.QVEL, int(a)) for a in m.jnt_dofadr[joints]],
        "gravity": [(kern.GRAVITY, i) for i in range(3)],
        "roll_pitch": [(kern.ROLL_PITCH, i) for i in range(2)],
        "gyro": [(kern.QVEL, free_v + 3 + i) for i in range(3)],
        "torso_velocity": [(kern.TORSO_VEL, i) for i in range(3)],
        "torso_height": [(kern.QPOS, free_q + 2)],
        "foot_contact": [(kern.CONTACT, int(robot.sensor(f"{f}_floor").start))
                         for f in robot.feet],
        "phase": [(kern.PHASE, 0), (kern.PHASE, 1)],
        "command": [(kern.COMMAND, i) for i in range(int(observe.spec.command_size))],
    }
    pairs = [p for c in observe.spec.channels for p in table[c]]
    return (np.array([p[0] for p in pairs], np.int32), np.array([p[1] for p in pairs], np.int32))


class ClosedLoopBatch:
    """The device side of ``nworld`` worlds of one run layout (module doc)."""

    def __init__(self, sim, nworld: int, layout: Layout) -> None:
        wp, mjw, m, phys = sim.wp, sim.physics.mjw, sim.model, sim.physics
        self.wp, self.sim, self.nworld, self.layout = wp, sim, nworld, layout
        o, a, nu, C = sim.observation_size, sim.action_size, m.nu, layout.nctrl
        ns = sim.nstate
        rec_floats = (C + 1) * (13 + (ns if layout.record_states else 0)) + C * a
        est = estimate_bytes(m, phys._data0, sim.device, nworld, 0, phys.nconmax, phys.njmax,
                             batches=1)
        needed = est.needed + nworld * 4 * (rec_floats + (layout.depth + 2) * nu + 6 * o)
        if est.free is not None and needed > est.free:
            raise InputError(f"closed loop on {sim.device}: a batch of {nworld} worlds needs "
                             f"about {needed / 1e9:.2f} GB, {est.free / 1e9:.2f} GB are free; "
                             "evaluate fewer individuals at once")
        f32, i32 = wp.float32, wp.int32
        with wp.ScopedDevice(sim.device):
            self.model = mjw.put_model(m, batch_sizes={f: nworld for f in layout.fields}
                                       or None)
            self.model.opt.warn_overflow = 0
            if phys.deterministic:
                self.model.opt.deterministic = int(mjw.DeterminismType.ALL) \
                    if hasattr(mjw, "DeterminismType") else True
            self.data = mjw.put_data(m, phys._data0, nworld=nworld, nconmax=phys.nconmax,
                                     njmax=phys.njmax)
            self.njmax = phys.njmax
            z = wp.zeros
            self.clock, self.peak, self.alive = z(2, dtype=i32), z(2, dtype=i32), z(1, dtype=i32)
            self.done, self.fall_step = z(nworld, dtype=i32), z(nworld, dtype=i32)
            self.latency, self.push_start = z(nworld, dtype=i32), z(nworld, dtype=i32)
            self.push_force = z(nworld, dtype=wp.vec3)
            self.ring = z((nworld, layout.depth, nu), dtype=f32)
            self.commands = z((nworld, max(sim.spec_command_size, 1)), dtype=f32)
            self.obs, self.actions = z((nworld, o), dtype=f32), z((nworld, a), dtype=f32)
            self.obs_sum = z((nworld, o), dtype=wp.float64)
            self.obs_sumsq = z((nworld, o), dtype=wp.float64)
            self.torso = z((nworld, C + 1, 13), dtype=f32)
            self.states = z((nworld, C + 1, ns) if layout.record_states else (1, 1, 1),
                            dtype=f32)
            self.sent = z((nworld, C, a) if layout.record_targets else (1, 1, 1), dtype=f32)
            d = self.data
            self.backup = (z_like(wp, d.time), z_like(wp, d.qpos), z_like(wp, d.qvel),
                           z_like(wp, d.sensordata), z(nworld, dtype=i32))
            self.columns = wp.array(sim.columns.astype(np.int32), dtype=i32)
            self.nominal = wp.array(sim.nominal.astype(np.float32), dtype=f32)
            self.lower = wp.array(np.asarray(sim.lower, np.float32), dtype=f32)
            self.upper = wp.array(np.asarray(sim.upper, np.float32), dtype=f32)
            self.kind = wp.array(sim.kind, dtype=i32)
            self.index = wp.array(sim.index, dtype=i32)
            self.layers = (DeviceLayers(wp, layout.spec, nworld) if layout.spec is not None
                           else None)
        self._graphs: dict[tuple, Any] = {}
        self._warm: set[tuple] = set()
        self._m = nworld

    # -- host round trips --------------------------------------------------------------------
    def upload(self, carry, alive: np.ndarray, c: int, k: int, per_row) -> None:
        """The carried state of ``alive`` (padded to ``nworld``) at control step ``c``."""
        wp, d, f32 = self.wp, self.data, np.float32
        self._m = m = alive.size
        rows = np.concatenate([alive, np.full(self.nworld - m, alive[-1])])
        with wp.ScopedDevice(self.sim.device):
            d.time.assign(carry.time[rows].astype(f32))
            d.qpos.assign(carry.qpos[rows].astype(f32))
            d.qvel.assign(carry.qvel[rows].astype(f32))
            d.sensordata.assign(carry.sensors[rows].astype(f32))
            d.qacc_warmstart.zero_()
            d.xfrc_applied.zero_()
            self.done.assign((np.arange(self.nworld) >= m).astype(np.int32))
            self.fall_step.assign(carry.fall_step[rows].astype(np.int32))
            self.latency.assign(per_row.latency[rows].astype(np.int32))
            self.push_start.assign(per_row.pushes.step[rows].astype(np.int32))
            self.push_force.assign(per_row.pushes.force_n[rows].astype(f32))
            self.ring.assign(carry.ring[rows].astype(f32))
            if per_row.commands is not None:
                self.commands.assign(per_row.commands[rows].astype(f32))
            self.obs_sum.assign(carry.obs_sum[rows])
            self.obs_sumsq.assign(carry.obs_sumsq[rows])
            for name, values in per_row.fields.items():
                getattr(self.model, name).assign(
                    np.ascontiguousarray(values[per_row.index[rows]]))
            self.clock.assign(np.array([c * k, c], dtype=np.int32))
            if self.layers is not None:
                self.layers.load(per_row.policy, rows)

    def download(self, carry, rec, alive: np.ndarray, c0: int, c: int, backup: bool) -> None:
        """The state of ``alive`` back into ``carry`` (at the start of control step ``c`` from
        the backup, else now) and the records of control steps ``c0 .. c - 1`` into ``rec``."""
        m, d = alive.size, self.data
        src = self.backup if backup else (d.time, d.qpos, d.qvel, d.sensordata, self.fall_step)
        carry.time[alive] = src[0].numpy()[:m]
        carry.qpos[alive] = src[1].numpy()[:m]
        carry.qvel[alive] = src[2].numpy()[:m]
        carry.sensors[alive] = src[3].numpy()[:m]
        carry.fall_step[alive] = src[4].numpy()[:m]
        carry.ring[alive] = self.ring.numpy()[:m]
        carry.obs_sum[alive] = self.obs_sum.numpy()[:m]
        carry.obs_sumsq[alive] = self.obs_sumsq.numpy()[:m]
        rec.torso[alive, c0 + 1:c + 1] = self.torso[:m].numpy()[:, c0 + 1:c + 1]
        if rec.states is not None:
            rec.states[alive, c0 + 1:c + 1] = self.states[:m].numpy()[:, c0 + 1:c + 1]
        if rec.targets is not None:
            hi = c + 1 if backup else c  # the redone step's targets were sent already
            rec.targets[alive, c0:hi] = self.sent[:m].numpy()[:, c0:hi]

    # -- one control step --------------------------------------------------------------------
    def _observe(self) -> None:
        wp, sim, d, o = self.wp, self.sim, self.data, self.sim.observation_size
        period = float(sim.observe.spec.phase_period_s)
        omega = 2.0 * np.pi / period if period > 0 else 0.0
        wp.launch(kern.observe, dim=(self.nworld, o),
                  inputs=[d.qpos, d.qvel, d.time, d.sensordata, self.commands, self.kind,
                          self.index, int(sim.model.jnt_qposadr[0]),
                          int(sim.model.jnt_dofadr[0]), omega], outputs=[self.obs])
        wp.launch(kern.moments, dim=(self.nworld, o), inputs=[self.obs, self.done],
                  outputs=[self.obs_sum, self.obs_sumsq])

    def _targets(self) -> None:
        self.wp.launch(kern.targets, dim=(self.nworld, self.sim.action_size),
                       inputs=[self.actions, self.columns, self.nominal, self.lower,
                               self.upper, self.clock, self.layout.depth,
                               int(self.layout.record_targets), self.done],
                       outputs=[self.ring, self.sent])

    def control_on_device(self) -> None:
        """Observe, act (the device policy) and send the targets: one captured phase."""
        layers = self.layers
        if layers is None:
            raise ValueError("control_on_device: this batch was laid out without a device "
                             "policy")

        def phase() -> None:
            self._observe()
            layers.launch(self.obs, self.actions)
            self._targets()
        self._run(("control",), phase)

    def observe_to_host(self) -> np.ndarray:
        with self.wp.ScopedDevice(self.sim.device):
            self._observe()
            return self.obs.numpy()

    def targets_from_host(self, actions: np.ndarray, at: np.ndarray) -> None:
        """The host policy's ``actions`` of batch rows ``at`` into the latency ring."""
        full = np.zeros((self.nworld, actions.shape[1]), dtype=np.float32)
        full[at] = actions
        with self.wp.ScopedDevice(self.sim.device):
            self.actions.assign(full)
            self._targets()

    def running(self, m: int) -> np.ndarray:
        """Which of the first ``m`` batch rows still run (``[m]`` bool)."""
        return self.done.numpy()[:m] == 0

    def physics(self, kk: int, mjw) -> tuple[int, np.ndarray | None]:
        """``kk`` physics steps and the records: (worlds still running, the peak contact and
        constraint counts when the buffers overflowed, else None)."""
        wp, d, sim, m = self.wp, self.data, self.sim, self.sim.model
        free_q = int(m.jnt_qposadr[0])

        def phase() -> None:
            for dst, src in zip(self.backup, (d.time, d.qpos, d.qvel, d.sensordata,
                                              self.fall_step), strict=True):
                wp.copy(dst, src)
            d.qacc_warmstart.zero_()
            self.peak.zero_()
            self.alive.zero_()
            d.overflow.zero_()
            cos_tilt = float(np.cos(sim.fall_tilt_rad))
            for _ in range(kk):
                wp.launch(kern.load_ctrl, dim=(self.nworld, m.nu),
                          inputs=[self.ring, self.latency, self.clock, sim.k,
                                  self.layout.depth, self.nominal], outputs=[d.ctrl])
                if self.layout.pushed:
                    wp.launch(kern.push, dim=self.nworld,
                              inputs=[self.clock, self.push_start, sim.push_steps,
                                      self.push_force, sim.robot_torso],
                              outputs=[d.xfrc_applied])
                mjw.step(self.model, d)
                wp.launch(kern.fall, dim=self.nworld,
                          inputs=[self.clock, d.qpos, free_q, float(sim.fall_height_m),
                                  cos_tilt, self.done, self.fall_step, d.nefc, d.nacon],
                          outputs=[self.peak])
                wp.launch(kern.advance, dim=1, inputs=[self.clock, 0])
            wp.launch(kern.record, dim=self.nworld,
                      inputs=[self.clock, d.time, d.qpos, d.qvel, free_q,
                              int(m.jnt_dofadr[0]), m.nq, m.nv, int(self.layout.record_states),
                              self.fall_step, self.done],
                      outputs=[self.torso, self.states, self.alive])
            wp.launch(kern.advance, dim=1, inputs=[self.clock, 1])
        self._run(("physics", kk), phase)
        with wp.ScopedDevice(sim.device):
            wp.synchronize_device(sim.device)
        peak = self.peak.numpy()
        bits = int(np.bitwise_or.reduce(d.overflow.numpy())) & sim.physics._grow_bits
        over = peak[0] > self.njmax or peak[1] > d.naconmax or bits
        return int(self.alive.numpy()[0]), (peak if over else None)

    def _run(self, key: tuple, phase) -> None:
        """``phase`` eagerly the first time (compiling its kernels), captured as a CUDA graph
        the second and replayed from then on; eagerly on the CPU device."""
        wp, sim = self.wp, self.sim
        with wp.ScopedDevice(sim.device):
            graph = self._graphs.get(key)
            if graph is None and key in self._warm and sim.physics.graphs:
                try:
                    with wp.ScopedCapture(device=sim.device) as cap:
                        phase()
                    graph = self._graphs[key] = cap.graph
                except RuntimeError:  # e.g. a driver without conditional graphs
                    sim.physics.graphs = False
            if graph is None:
                phase()
                self._warm.add(key)
            else:
                wp.capture_launch(graph)


def z_like(wp, array) -> Any:
    return wp.zeros(array.shape, dtype=array.dtype)
