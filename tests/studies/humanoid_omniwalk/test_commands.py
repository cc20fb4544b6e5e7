"""Command schedules and tracking (studies/humanoid_omniwalk/commands.py)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.studies.humanoid_omniwalk.commands import (
    CommandDraw,
    command_schedule,
    heading_at,
    schedules,
    tracking,
)

T = np.arange(0, 20, 0.02)


@settings(max_examples=30, deadline=None, derandomize=True, database=None)
@given(seed=st.integers(0, 2**40))
def test_a_schedule_is_its_seeds_alone_in_range_and_ramped(seed):
    d = CommandDraw()
    c = command_schedule(d, seed, T)
    np.testing.assert_array_equal(c, command_schedule(d, seed, T))
    np.testing.assert_array_equal(schedules(d, np.array([seed, 7, seed]), T)[2], c)
    assert np.all(c[:, 0] >= d.vx_min - 1e-12) and np.all(c[:, 0] <= d.vx_max + 1e-12)
    assert np.all(np.abs(c[:, 1]) <= d.vy_max) and np.all(np.abs(c[:, 2]) <= d.yaw_rate_max)
    assert np.all(c[0] == 0)  # ramps from standing
    # a ramp of ramp_s: no step bigger than the full range over ramp_s / dt steps
    span = np.array([d.vx_max - d.vx_min, 2 * d.vy_max, 2 * d.yaw_rate_max])
    assert np.all(np.abs(np.diff(c, axis=0)) <= span * 0.02 / d.ramp_s + 1e-12)


@settings(max_examples=20, deadline=None, derandomize=True, database=None)
@given(seed=st.integers(0, 2**40), preview=st.sampled_from([0.04, 0.1, 0.3, 0.5]))
def test_a_preview_is_the_ramp_ahead_never_the_next_command(seed, preview):
    d = CommandDraw()
    plain, ahead = command_schedule(d, seed, T), command_schedule(d, seed, T, preview)
    np.testing.assert_array_equal(command_schedule(d, seed, T, 0.0), plain)
    np.testing.assert_array_equal(schedules(d, np.array([seed]), T, preview)[0], ahead)
    # each command at once (a microsecond on: the first is given at 0 s)
    target = command_schedule(replace(d, ramp_s=1e-9), seed, T + 1e-6)
    # between the ramp now and the command given now: never the next command
    assert np.all(ahead >= np.minimum(plain, target) - 1e-12)
    assert np.all(ahead <= np.maximum(plain, target) + 1e-12)
    # where no new command comes within the preview, it is the ramp that much later
    later = command_schedule(d, seed, T + preview)
    k = int(round(preview / 0.02))
    same = np.array([np.all(target[i:i + k + 1] == target[i]) for i in range(len(T) - k)])
    np.testing.assert_allclose(ahead[:len(same)][same], later[:len(same)][same], atol=1e-12)
    assert same.mean() > 0.8 and np.any(ahead != plain)


def test_schedules_hold_commands_for_two_to_four_seconds_and_mix_kinds():
    d = CommandDraw()
    kinds = set()
    for seed in range(40):
        c = command_schedule(d, seed, T)
        steady = c[np.arange(len(T)) % 5 == 0]
        for row in steady:
            kinds.add(tuple(np.flatnonzero(np.abs(row) > 1e-12)))
        changes = np.flatnonzero(np.abs(np.diff(c, axis=0)).sum(axis=1) > 0)
        starts = changes[np.r_[True, np.diff(changes) > 1]] * 0.02
        assert np.all(np.diff(starts) >= d.hold_min_s - 0.05)
    assert {(0,), (1,), (2,), (0, 1, 2)} <= kinds


def test_tracking_reads_the_velocity_in_the_heading_frame():
    """A torso walking at 0.2 m/s forward and 0.1 m/s to its left while turning at 0.5 rad/s."""
    dt, C, W = 0.02, 200, 24
    t = np.arange(C + 1) * dt
    yaw = 0.5 * t
    v_world = np.stack([0.2 * np.cos(yaw) - 0.1 * np.sin(yaw),
                        0.2 * np.sin(yaw) + 0.1 * np.cos(yaw)], -1)
    pos = np.concatenate([[[0, 0]], np.cumsum(v_world[:-1] * dt, axis=0)])
    torso = np.zeros((1, C + 1, 13))
    torso[0, :, :2] = pos
    torso[0, :, 3], torso[0, :, 6] = np.cos(yaw / 2), np.sin(yaw / 2)
    cmd = np.tile([0.2, 0.1, 0.5], (1, C, 1))
    tr = tracking(torso, cmd, W, dt)
    np.testing.assert_allclose(tr.yaw_rate, 0.5, atol=1e-9)
    np.testing.assert_allclose(tr.vx, 0.2, atol=3e-3)
    np.testing.assert_allclose(tr.vy, 0.1, atol=3e-3)
    ev, ew = tr.errors()
    assert ev.max() < 5e-3 and ew.max() < 1e-9


def test_kind_weights_choose_the_kinds_and_the_defaults_draw_as_before():
    fwd = CommandDraw(vx_min=0.25, vx_max=0.45, kind_weights=(1.0, 0.0, 0.0, 0.0, 0.0))
    for seed in range(20):
        c = command_schedule(fwd, seed, T)
        assert np.all(c[:, 1:] == 0) and np.all(c[:, 0] <= 0.45 + 1e-12)
        after_first_ramp = fwd.ramp_s <= T  # (the first command ramps up from standing)
        assert np.all(c[after_first_ramp, 0] >= 0.25 - 1e-12)
    # the default weights, spelled out, draw the very same schedules
    spelled = CommandDraw(kind_weights=(0.3, 0.15, 0.15, 0.3, 0.1))
    for seed in range(5):
        np.testing.assert_array_equal(command_schedule(spelled, seed, T),
                                      command_schedule(CommandDraw(), seed, T))


def test_command_weights_are_checked_and_normalised():
    import pytest

    from evomotion.errors import InputError
    from evomotion.studies.humanoid_omniwalk.problem import OmniWalkConfig

    cfg = OmniWalkConfig(command_weights=(2.0, 0.0, 0.0, 0.0, 0.0), vx_min=0.1)
    cfg.validate()
    assert cfg.commands().kind_weights == (1.0, 0.0, 0.0, 0.0, 0.0)
    assert OmniWalkConfig().commands().kind_weights == (0.3, 0.15, 0.15, 0.3, 0.1)
    for bad, match in (((1.0, 0.0), "expected 5 weights"),
                       ((1.0, -1.0, 0.0, 0.0, 0.0), r"command_weights\[1\]"),
                       ((0.0,) * 5, "at least one weight"),
                       ((float("nan"), 0.0, 0.0, 0.0, 1.0), r"command_weights\[0\]")):
        with pytest.raises(InputError, match=match) as e:
            OmniWalkConfig(command_weights=bad).validate()
        assert "\n" not in str(e.value)
    with pytest.raises(InputError, match="problem.vx_min"):
        OmniWalkConfig(vx_min=0.5, vx_max=0.45).validate()


def test_heading_at_reads_the_control_step_holding_each_time():
    """Yaw ``ψ_c = 0.1 c`` at control step ``c`` (quaternion about z): times inside step 3 read
    0.3, times past the record read its last row."""
    yaw = 0.1 * np.arange(6)
    torso = np.zeros((2, 6, 7))
    torso[..., 3], torso[..., 6] = np.cos(yaw / 2), np.sin(yaw / 2)
    np.testing.assert_allclose(heading_at(torso, np.array([0.061, 9.0]), 0.02), [0.3, 0.5])
