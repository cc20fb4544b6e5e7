"""A fake ``naoqi`` module for the NAOqi policy runner's tests (no NAO here).

``install(memory_values)`` makes a module named ``naoqi`` (a test puts it into ``sys.modules``
with ``monkeypatch.setitem``) whose ``ALProxy(name, ip, port)`` returns one shared fake per service:

- ``ALMemory``: ``getListData(keys)`` serves the values fed to it (:meth:`FakeMemory.feed`, or
  a ``stream`` of ``{key: value}`` frames picked by a fake clock), and records every call;
- ``DCM``: ``getTime(delay_ms)`` (the fake clock in ms + delay), ``createAlias``, ``setAlias``
  (records the targets, checking the "time-separate" layout the runner uses);
- ``ALMotion``: ``setStiffnesses``, ``angleInterpolationWithSpeed`` (recorded).
"""

from __future__ import annotations

import types


class FakeClock:
    """Seconds, advanced by ``sleep`` (the runner's ``clock`` and ``sleep``)."""

    def __init__(self, t: float = 0.0) -> None:
        self.t = t

    def __call__(self) -> float:
        return self.t

    def sleep(self, seconds: float) -> None:
        assert seconds >= 0
        self.t += seconds


class FakeMemory:
    def __init__(self, values: dict[str, float] | None = None) -> None:
        self.values = dict(values or {})
        self.stream: list[dict[str, float]] | None = None
        self.clock: FakeClock | None = None
        self.period_s = 0.0
        self.calls: list[list[str]] = []

    def feed(self, values: dict[str, float]) -> None:
        self.values.update(values)

    def getListData(self, keys):  # noqa: N802 (NAOqi's name)
        self.calls.append(list(keys))
        frame = self.values
        if self.stream is not None:
            assert self.clock is not None
            frame = self.stream[int(round(self.clock.t / self.period_s))]
        return [frame[k] for k in keys]  # a missing key fails the test, as NAOqi would


class FakeDCM:
    def __init__(self, clock: FakeClock) -> None:
        self.clock = clock
        self.aliases: dict[str, list[str]] = {}
        self.sent: list[tuple[int, list[float]]] = []

    def getTime(self, delay_ms):  # noqa: N802
        return int(round(self.clock.t * 1000.0)) + int(delay_ms)

    def createAlias(self, args):  # noqa: N802
        name, keys = args
        assert all(k.endswith("/Position/Actuator/Value") for k in keys)
        self.aliases[name] = list(keys)

    def setAlias(self, args):  # noqa: N802
        name, update, layout, importance, times, values = args
        assert name in self.aliases and update == "ClearAll" and layout == "time-separate"
        assert importance == 0 and len(times) == 1
        assert len(values) == len(self.aliases[name]) and all(len(v) == 1 for v in values)
        self.sent.append((times[0], [v[0] for v in values]))


class FakeMotion:
    def __init__(self) -> None:
        self.stiffness: dict[str, float] = {}
        self.poses: list[tuple[list[str], list[float], float]] = []

    def setStiffnesses(self, names, value):  # noqa: N802
        for n in names:
            self.stiffness[n] = float(value)

    def angleInterpolationWithSpeed(self, names, angles, speed):  # noqa: N802
        assert all(self.stiffness.get(n) == 1.0 for n in names), "stiffness before moving"
        self.poses.append((list(names), list(angles), speed))


def install(values: dict[str, float] | None = None, clock: FakeClock | None = None):
    """The fake ``naoqi`` module (see the module doc)."""
    clock = clock or FakeClock()
    module = types.ModuleType("naoqi")
    module.clock = clock
    module.memory, module.dcm, module.motion = FakeMemory(values), FakeDCM(clock), FakeMotion()
    module.connections = []
    services = {"ALMemory": module.memory, "DCM": module.dcm, "ALMotion": module.motion}

    def ALProxy(name, ip, port):  # noqa: N802
        module.connections.append((name, ip, port))
        return services[name]

    module.ALProxy = ALProxy
    return module
