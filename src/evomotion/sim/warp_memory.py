"""Device memory of a MuJoCo Warp batch, estimated before the batch is allocated.

A MuJoCo Warp ``Data`` of ``nworld`` worlds takes ``fixed + nworld x per_world`` bytes for a
given model and contact/constraint buffer sizes. Both terms are measured once by allocating
``Data`` for one and for two worlds (a few hundred kB) and adding up the bytes of every Warp
array in it; the segment's control and recording buffers (float32) come on top. The early stop
packs active robots into power-of-two batches (:func:`bucket_size`), kept side by side, so a run
of batch ``B`` needs at most ``2 x bucket_size(B)`` worlds' worth.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import mujoco

from evomotion.sim.state import state_size
from evomotion.sysmem import available_bytes

_PROBES: dict[tuple, tuple[mujoco.MjModel, tuple[int, int]]] = {}


@dataclass(frozen=True)
class MemoryEstimate:
    needed: int  # bytes
    free: int | None  # bytes free on the device now, None when it cannot be told
    device: str


def bucket_size(n: int) -> int:
    """The smallest power of two ``>= n`` (the batch ``n`` trajectories are packed into)."""
    return 1 << max(int(n) - 1, 0).bit_length()


def array_bytes(obj: Any) -> int:
    """Bytes of every Warp array in a MuJoCo Warp ``Data``/``Model`` (nested dataclasses too)."""
    import warp as wp

    total = 0
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name, None)
        if isinstance(v, wp.array):
            total += int(v.capacity)
        elif dataclasses.is_dataclass(v) and not isinstance(v, type):
            total += array_bytes(v)
    return total


def _probe(model: mujoco.MjModel, data0: mujoco.MjData, device: str, nconmax: int,
           njmax: int) -> tuple[int, int]:
    """(fixed bytes, bytes per world) of MuJoCo Warp ``Data`` (and the model) for ``model``."""
    key = (id(model), device, nconmax, njmax)
    cached = _PROBES.get(key)
    if cached is not None and cached[0] is model:  # not another model at a reused id
        return cached[1]
    import mujoco_warp as mjw
    import warp as wp

    with wp.ScopedDevice(device):
        one = array_bytes(mjw.put_data(model, data0, nworld=1, nconmax=nconmax, njmax=njmax))
        two = array_bytes(mjw.put_data(model, data0, nworld=2, nconmax=nconmax, njmax=njmax))
        model_bytes = array_bytes(mjw.put_model(model))
    per_world = max(two - one, 0)
    sizes = (one - per_world + model_bytes, per_world)
    _PROBES[key] = (model, sizes)
    return sizes


def free_bytes(device: str) -> int | None:
    """Free memory of a Warp device now (CUDA: the driver's count; CPU: ``MemAvailable``)."""
    if device.startswith("cuda"):
        import warp as wp

        return int(wp.get_device(device).free_memory)
    return available_bytes()


def estimate_bytes(model: mujoco.MjModel, data0: mujoco.MjData, device: str, batch: int,
                   nstep: int, nconmax: int, njmax: int, batches: int = 2) -> MemoryEstimate:
    """Device bytes for ``batches`` batches of ``bucket_size(batch)`` worlds recording
    ``nstep`` steps each (controls, states and sensors in float32)."""
    fixed, per_world = _probe(model, data0, device, nconmax, njmax)
    nstate = state_size(model)
    buffers = 4 * int(nstep) * (model.nu + nstate + model.nsensordata)
    needed = fixed + batches * bucket_size(batch) * (per_world + buffers)
    return MemoryEstimate(int(needed), free_bytes(device), device)
