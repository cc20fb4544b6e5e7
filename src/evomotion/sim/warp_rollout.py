"""Batched open-loop physics with MuJoCo Warp (``problem.backend = "warp"``).

The same model, the same precomputed ``ctrl[batch, nstep, nu]`` in and the same recorded
``states[batch, nstep, nstate]`` (``mjSTATE_FULLPHYSICS``: time, qpos, qvel) and sensor values
out as :class:`~evomotion.sim.rollout.BatchSimulator` (``mujoco.rollout``), so a study does not
change. Every world of the batch is stepped at once by :func:`mujoco_warp.step` on a CUDA
device (or, for tests and machines without a GPU, on Warp's CPU device); on CUDA one physics
step is captured once as a graph and replayed for every step.

Early stopping costs nothing: between segments the still-active robots are packed into the
smallest batch of a power-of-two size that holds them (padding repeats the last active row,
whose results are dropped), so fallen robots are not stepped. One device batch (MuJoCo Warp
``Data``, control and recording buffers) is kept per batch size, at most ``2 x`` the largest.

Perturbed worlds (:func:`evomotion.sim.worlds.simulate_worlds`) give each trajectory its
own copy of the model fields that differ between the worlds (MuJoCo Warp's batched model
fields, indexed by world) and its torso push, applied on the device in the step it is due.

Contact and constraint buffers are sized ``nconmax`` contacts and ``njmax`` rows per world;
when a segment used more, the buffers grow and the segment is simulated again, so no contact
is ever dropped. Precision is MuJoCo Warp's float32 (MuJoCo's CPU engine is float64); the
tolerances between the two are measured in ``tests/sim/test_warp_backend.py``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from evomotion.errors import InputError
from evomotion.sim.rollout import SegmentedSimulator
from evomotion.sim.state import STATE_SPEC
from evomotion.sim.warp_memory import MemoryEstimate, bucket_size, estimate_bytes


def import_warp() -> tuple[Any, Any]:
    """``(warp, mujoco_warp)``, or a one-line :class:`InputError` naming the extra."""
    try:
        import warp as wp

        # before MuJoCo Warp initialises Warp: no banner, ...
        wp.config.quiet = True  # type: ignore[attr-defined]  # (not in its stub)
        if hasattr(wp, "LOG_WARNING"):
            wp.config.log_level = max(wp.config.log_level, wp.LOG_WARNING)  # ... no timings
        import mujoco_warp as mjw
    except ImportError as e:
        raise InputError("problem.backend = 'warp' needs MuJoCo Warp: pip install "
                         f"'evomotion[gpu]' ({e})") from None
    return wp, mjw


def resolve_device(name: str = "") -> str:
    """``name`` (``"cpu"``, ``"cuda"``, ``"cuda:1"``), or with ``""`` the first CUDA device
    when there is one, else ``"cpu"``; a one-line :class:`InputError` for an unknown device."""
    wp, _ = import_warp()
    if not name:
        return "cuda:0" if wp.is_cuda_available() else "cpu"
    try:
        return str(wp.get_device(name))
    except (RuntimeError, ValueError) as e:
        devices = ", ".join(str(d) for d in wp.get_devices())
        raise InputError(f"problem.warp_device: unknown device {name!r}; available: "
                         f"{devices} ({e})") from None


@dataclass
class _Batch:
    """One device batch: MuJoCo Warp model and data of ``nworld`` worlds and its buffers."""

    nworld: int
    model: Any
    data: Any
    ctrl: Any  # [nworld, seg, nu]
    states: Any  # [nworld, seg, nstate]
    sensors: Any  # [nworld, seg, nsensordata]
    step: Any  # segment step counter (device)
    peak: Any  # (max constraint rows of a world, max contacts of the batch)
    push_step: Any = None
    push_force: Any = None
    push_body: int = 0
    graph: Any = None
    fields: tuple[str, ...] = field(default_factory=tuple)


class WarpSimulator(SegmentedSimulator):
    """:class:`~evomotion.sim.rollout.BatchSimulator`'s interface on MuJoCo Warp."""

    backend = "warp"

    def __init__(self, model: mujoco.MjModel, device: str = "", deterministic: bool = False,
                 nconmax: int = 16, njmax: int = 0) -> None:
        self.wp, self.mjw = import_warp()
        if model.na:
            raise InputError("problem.backend = 'warp': models with actuator activations are "
                             "not supported (the recorded state has no act)")
        self.model = model
        self.device = resolve_device(device)
        self.deterministic = bool(deterministic)
        self.nthread = 1  # one device: evaluators' worker count does not apply
        self.nstate = mujoco.mj_stateSize(model, STATE_SPEC)
        self.nconmax = int(nconmax)
        self.njmax = int(njmax) or self.nconmax * 6 + 2 * model.njnt
        self.steps_simulated = 0
        self.rollout_seconds = 0.0
        self.regrown = 0  # times the contact/constraint buffers grew
        self._batches: dict[tuple, _Batch] = {}
        self._data0 = mujoco.MjData(model)  # no contacts yet: any nconmax/njmax is allowed
        self.graphs = self.device.startswith("cuda")
        ov = self.mjw.OverflowType
        #: overflows that lose contacts or constraint rows: the buffers grow, the segment reruns
        self._grow_bits = int(ov.NEFC | ov.NJMAX_NNZ | ov.BROADPHASE | ov.NARROWPHASE | ov.CCD)
        try:
            with self.wp.ScopedDevice(self.device):
                self.mjw.put_model(model)
        except (NotImplementedError, ValueError, TypeError) as e:
            raise InputError(f"problem.backend = 'warp': MuJoCo Warp cannot simulate this "
                             f"model ({' '.join(str(e).split())})") from None

    # -- the BatchSimulator interface (run, run_until, with: SegmentedSimulator) ------------
    def run_with_sensors(self, initial_state: np.ndarray,
                         ctrl: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        batch = ctrl.shape[0]
        init = np.broadcast_to(initial_state, (batch, self.nstate))
        return self.segment(init, ctrl)

    def close(self) -> None:
        self._batches.clear()

    # -- memory ----------------------------------------------------------------------------
    def memory(self, batch: int, nstep: int) -> MemoryEstimate:
        """Device bytes for a batch of ``batch`` trajectories of ``nstep`` steps (every
        power-of-two batch the early stop may pack them into included) and the free bytes."""
        return estimate_bytes(self.model, self._data0, self.device, batch, nstep,
                              self.nconmax, self.njmax)

    # -- one segment -----------------------------------------------------------------------
    def segment(self, init: np.ndarray, ctrl: np.ndarray,
                fields: dict[str, np.ndarray] | None = None,
                push: tuple[np.ndarray, np.ndarray, int] | None = None
                ) -> tuple[np.ndarray, np.ndarray]:
        """(``states[n, T, nstate]``, ``sensors[n, T, nsensordata]``) of ``n`` trajectories
        from ``init[n, nstate]`` under ``ctrl[n, T, nu]``; ``fields``: per-trajectory values
        ``[n, ...]`` of batched model fields; ``push``: (``step[n]`` within the segment or -1,
        ``force[n, 3]`` N, body id)."""
        n, nseg = ctrl.shape[:2]
        if n == 0 or nseg == 0:
            return (np.empty((n, nseg, self.nstate)),
                    np.empty((n, nseg, self.model.nsensordata)))
        t0 = time.perf_counter()
        while True:
            b = self._batch(bucket_size(n), nseg, tuple(sorted(fields or {})),
                            None if push is None else int(push[2]))
            states, sensors, peak, overflow = self._simulate(b, init, ctrl, fields, push)
            if peak[0] <= self.njmax and peak[1] <= b.data.naconmax and not overflow:
                break
            self._grow(peak, b)
        self.rollout_seconds += time.perf_counter() - t0
        self.steps_simulated += n * nseg
        return states, sensors

    def _simulate(self, b: _Batch, init, ctrl, fields, push):
        wp, d = self.wp, b.data
        n, nseg = ctrl.shape[:2]
        rows = np.minimum(np.arange(b.nworld), n - 1)  # padding repeats the last row
        init = np.asarray(init, dtype=np.float64)[rows]
        nq, nv = self.model.nq, self.model.nv
        d.time.assign(init[:, 0].astype(np.float32))
        d.qpos.assign(init[:, 1:1 + nq].astype(np.float32))
        d.qvel.assign(init[:, 1 + nq:1 + nq + nv].astype(np.float32))
        d.qacc_warmstart.zero_()
        d.xfrc_applied.zero_()
        c = np.zeros(b.ctrl.shape, dtype=np.float32)
        c[:, :nseg] = ctrl[rows]
        b.ctrl.assign(c)
        for name, values in (fields or {}).items():
            getattr(b.model, name).assign(np.ascontiguousarray(np.asarray(values)[rows]))
        if push is not None:
            b.push_step.assign(np.asarray(push[0], np.int32)[rows])
            b.push_force.assign(np.asarray(push[1], np.float32)[rows])
        b.step.zero_()
        b.peak.zero_()
        d.overflow.zero_()
        with wp.ScopedDevice(self.device):
            for _ in range(nseg):
                if b.graph is not None:
                    wp.capture_launch(b.graph)
                else:
                    self._one_step(b)
            wp.synchronize_device(self.device)
        states = b.states.numpy()[:n, :nseg].astype(np.float64)
        sensors = b.sensors.numpy()[:n, :nseg].astype(np.float64)
        overflow = int(np.bitwise_or.reduce(d.overflow.numpy()[:n])) & self._grow_bits
        return states, sensors, b.peak.numpy(), overflow

    def _one_step(self, b: _Batch) -> None:
        wp, k, d, m = self.wp, _kernels(), b.data, self.model
        wp.launch(k.load_ctrl, dim=(b.nworld, m.nu), inputs=[b.ctrl, b.step], outputs=[d.ctrl])
        if b.push_step is not None:
            wp.launch(k.push, dim=b.nworld, inputs=[b.step, b.push_step, b.push_force,
                                                    b.push_body], outputs=[d.xfrc_applied])
        self.mjw.step(b.model, d)
        wp.launch(k.store, dim=b.nworld,
                  inputs=[b.step, d.time, d.qpos, d.qvel, d.sensordata, m.nq, m.nv,
                          m.nsensordata, d.nefc, d.nacon],
                  outputs=[b.states, b.sensors, b.peak])
        wp.launch(k.advance, dim=1, inputs=[b.step])

    def _grow(self, peak: np.ndarray, b: _Batch) -> None:
        """Enlarge the per-world buffers past what a segment used and drop every batch."""
        per_world_contacts = int(np.ceil(peak[1] / b.nworld))
        self.nconmax = max(2 * self.nconmax, 2 * per_world_contacts)
        self.njmax = max(2 * self.njmax, 2 * int(peak[0]))
        self.regrown += 1
        self._batches.clear()

    def _batch(self, nworld: int, nseg: int, fields: tuple[str, ...],
               push_body: int | None) -> _Batch:
        key = (nworld, fields, push_body)
        b = self._batches.get(key)
        if b is not None and b.ctrl.shape[1] >= nseg:
            return b
        wp, mjw, m = self.wp, self.mjw, self.model
        est = estimate_bytes(m, self._data0, self.device, nworld, nseg, self.nconmax,
                             self.njmax, batches=1)
        if est.free is not None and est.needed > est.free:
            raise InputError(f"problem.backend = 'warp': a batch of {nworld} worlds needs "
                             f"about {est.needed / 1e9:.2f} GB on {self.device}, "
                             f"{est.free / 1e9:.2f} GB are free; lower problem.batch_rollouts")
        with wp.ScopedDevice(self.device):
            wm = mjw.put_model(m, batch_sizes={f: nworld for f in fields} or None)
            wm.opt.warn_overflow = 0  # no printf from the kernels: overflows are read above
            if self.deterministic:
                wm.opt.deterministic = int(mjw.DeterminismType.ALL) \
                    if hasattr(mjw, "DeterminismType") else True
            wd = mjw.put_data(m, self._data0, nworld=nworld, nconmax=self.nconmax,
                              njmax=self.njmax)
            f32 = wp.float32
            b = _Batch(nworld, wm, wd,
                       wp.zeros((nworld, nseg, m.nu), dtype=f32),
                       wp.zeros((nworld, nseg, self.nstate), dtype=f32),
                       wp.zeros((nworld, nseg, m.nsensordata), dtype=f32),
                       wp.zeros(1, dtype=wp.int32), wp.zeros(2, dtype=wp.int32), fields=fields)
            if push_body is not None:
                b.push_body = push_body
                b.push_step = wp.full(nworld, -1, dtype=wp.int32)
                b.push_force = wp.zeros(nworld, dtype=wp.vec3)
            if self.graphs:  # compile every kernel outside the capture, then capture a step
                self._one_step(b)
                try:
                    with wp.ScopedCapture(device=self.device) as cap:
                        self._one_step(b)
                    b.graph = cap.graph
                except RuntimeError:  # e.g. a driver without conditional graphs: step by step
                    b.graph = None
                    self.graphs = False
        self._batches[key] = b
        return b

    def record(self) -> dict[str, Any]:
        """What a run folder records about this backend (``physics.json``)."""
        return backend_record(self)


def backend_record(sim: WarpSimulator) -> dict[str, Any]:
    import mujoco_warp as mjw
    import warp

    det = sim.deterministic
    cpu = sim.device == "cpu"
    implemented = _deterministic_contacts(mjw)
    if cpu:
        guarantee = ("bit-identical run to run and whatever the batch (Warp's CPU device runs "
                     "every kernel in a fixed order)")
    elif det and implemented:
        guarantee = "bit-identical run to run on the same GPU and software versions"
    else:
        guarantee = ("not guaranteed bit-identical run to run on a GPU: contact and constraint "
                     "order come from atomics" + (" (this MuJoCo Warp does not implement the "
                                                  "deterministic contact sort)" if det else ""))
    return {
        "backend": "warp", "device": sim.device, "precision": "float32",
        "mujoco_warp": getattr(mjw, "__version__", "?"),
        "warp": getattr(warp, "__version__", "?"), "mujoco": mujoco.__version__,
        "deterministic": det, "deterministic_contacts_implemented": implemented,
        "guarantee": guarantee + "; not bit-identical to backend 'cpu' (float64)",
    }


def _deterministic_contacts(mjw) -> bool:
    """Whether this MuJoCo Warp really sorts contacts in deterministic mode (4.0.0's
    ``_sort_contacts`` is a stub)."""
    import inspect

    try:
        from mujoco_warp._src import collision_driver

        src = inspect.getsource(collision_driver._sort_contacts)
    except (ImportError, AttributeError, OSError, TypeError):
        return False
    body = [ln.strip() for ln in src.splitlines()[1:]
            if ln.strip() and not ln.strip().startswith(("#", '"""'))]
    return body != ["pass"]


_KERNELS = None


def _kernels():
    global _KERNELS
    if _KERNELS is None:
        from evomotion.sim import warp_kernels

        _KERNELS = warp_kernels
    return _KERNELS
