"""compare's steady tracking windows: a one-cycle window counts once it begins SETTLE_S after
the command last changed (the episode's start counts as a change)."""

import numpy as np
import pytest

from evomotion.studies.humanoid_omniwalk.compare import steady_windows


def test_a_window_is_steady_once_it_begins_settle_steps_after_the_change():
    C, W, S = 40, 5, 3
    cmds = np.zeros((2, C, 3))
    cmds[0, 10:, 0] = 0.3  # one change, at control step 10
    cmds[1, :, 2] = 1.0  # none after the start
    got = steady_windows(cmds, W, S)
    ends = np.arange(W, C + 1)
    assert got.shape == (2, ends.size)
    want0 = ((ends >= W + S) & (ends <= 10)) | (ends >= 10 + W + S)
    np.testing.assert_array_equal(got[0], want0)
    np.testing.assert_array_equal(got[1], ends >= W + S)


def test_a_ramp_keeps_the_windows_unsteady_until_it_ends():
    C, W, S = 60, 4, 2
    cmds = np.zeros((1, C, 3))
    cmds[0, 20:30, 1] = np.linspace(0.02, 0.2, 10)  # a ramp over steps 20-29, then held
    cmds[0, 30:, 1] = 0.2
    got = steady_windows(cmds, W, S)[0]
    ends = np.arange(W, C + 1)
    during = ends > 20  # the windows that see the ramp (the earlier ones end before it)
    np.testing.assert_array_equal(got[during], ends[during] >= 29 + W + S)
    assert got[(ends >= W + S) & ~during].all()


def test_a_relative_error_of_a_quantity_never_commanded_is_none_not_a_huge_percentage():
    """A forward-only run commands no yaw rate: its relative yaw-rate error was the error over
    a sum of rounding errors (2e15 %); it is None, and the table shows a dash."""
    from evomotion.studies.humanoid_omniwalk.compare import _pct, _relative

    assert _relative(np.array([0.02, 0.03]), np.array([1e-17, 0.0])) is None
    assert _relative(np.array([0.02, 0.03]), np.array([0.25, 0.25])) == pytest.approx(0.1)
    assert _pct(None) == "–" and _pct(0.237) == "24 %"
