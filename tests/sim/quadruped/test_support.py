"""The support margin from contact forces on hand-made contact sets."""

import math

import numpy as np

from evomotion.sim.quadruped import support_margin, support_margins

SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


def test_equal_forces_on_a_square_put_the_cop_in_the_middle() -> None:
    assert math.isclose(support_margin(SQUARE, [1, 1, 1, 1]), 0.5)


def test_unequal_forces_shift_the_cop() -> None:
    # COP = (0.75, 0.5): 0.25 from the right edge
    assert math.isclose(support_margin(SQUARE, [1, 3, 3, 1]), 0.25)
    # loads symmetric about the centre keep the COP there
    assert math.isclose(support_margin(SQUARE, [1, 0.5, 1, 0.5]), 0.5)


def test_feet_out_of_contact_are_dropped_from_the_hull() -> None:
    # foot 3 carries nothing: triangle (0,0), (1,0), (1,1); COP (2/3, 1/3) of equal forces
    m = support_margin(SQUARE, [1, 1, 1, 0])
    assert math.isclose(m, (2 / 3 - 1 / 3) / math.sqrt(2))
    # below the threshold counts as out of contact too; fewer than 3 feet: undefined
    assert math.isclose(support_margin(SQUARE, [1, 1, 1, 0.01], min_force=0.05), m)
    assert math.isnan(support_margin(SQUARE, [1, 0, 1, 0]))


def test_cop_on_an_edge_and_collinear_feet_give_zero() -> None:
    # loads only on feet 0 and 2 (the diagonal) with foot 1 barely touching: COP ~ on edge 0-2
    assert abs(support_margin(SQUARE, [1, 1e-9, 1, 0])) < 1e-8
    line = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]])
    assert support_margin(line, [1, 1, 1, 1]) == 0.0


def test_vectorised_over_time_and_order_free() -> None:
    rng = np.random.default_rng(0)
    pts = rng.uniform(-1, 1, (50, 4, 2))
    f = rng.uniform(0, 1, (50, 4))
    m, cop = support_margins(pts, f)
    perm = [2, 0, 3, 1]
    m2, cop2 = support_margins(pts[:, perm], f[:, perm])
    np.testing.assert_allclose(m, m2, atol=1e-12)
    np.testing.assert_allclose(cop, cop2, atol=1e-12)
    assert (m >= -1e-12).all()  # pushing forces keep the COP inside the hull
    assert all(math.isclose(support_margin(pts[k], f[k]), m[k], abs_tol=1e-12)
               for k in range(5))
