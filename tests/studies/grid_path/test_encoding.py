"""The paper's perpendicular encoding, its operators and the fitness."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.studies.grid_path.encoding import PerpendicularEncoding, parts_from_m
from evomotion.studies.grid_path.geometry import polyline_segments_valid
from evomotion.studies.grid_path.operators import PathOperators
from evomotion.studies.grid_path.problem import GridPathConfig, GridPathProblem
from evomotion.studies.grid_path.solvers import encoding_optimum


@pytest.mark.parametrize(("name", "m", "genes"), [("seed10a", 1.2, 6), ("seed15", 1.1, 11),
                                                  ("seed20", 1.05, 17)])
def test_m_sets_the_perpendiculars(name, m, genes):
    p = GridPathProblem(GridPathConfig(map=name, m=m))
    assert p.genome.dim == genes
    spacing = p.enc.length / p.enc.n_parts
    assert spacing >= m * np.sqrt(2) - 1e-9  # never the same cell on two perpendiculars
    assert parts_from_m(p.enc.length, m) == genes + 1


def test_decode_geometry_and_inverse():
    p = GridPathProblem(GridPathConfig(map="seed15", m=1.1, mode="continuous"))
    enc = p.enc
    x = p.genome.sample(np.random.default_rng(0), 7)
    poly = enc.decode(x)
    assert poly.shape == (7, enc.n_parts + 1, 2)
    assert np.allclose(poly[:, 0], enc.start) and np.allclose(poly[:, -1], enc.goal)
    inner = poly[:, 1:-1]
    # each P_i lies on its perpendicular: its projection on SG is x'_i
    xprime = (inner - enc.start) @ enc.direction
    assert np.allclose(xprime, np.arange(1, enc.n_parts) * enc.length / enc.n_parts)
    assert np.allclose(np.stack([enc.to_genes(q) for q in inner]), x)
    lo, hi = enc.decode(p.genome.lower[None])[0], enc.decode(p.genome.upper[None])[0]
    for q in (lo, hi):  # bounds are the perpendiculars' ends on the map border
        assert np.all(q >= -1e-6) and np.all(q <= 15 + 1e-6)
        on_border = np.isclose(q[1:-1], 0, atol=1e-5) | np.isclose(q[1:-1], 15, atol=1e-5)
        assert on_border.any(axis=1).all()
    d = PerpendicularEncoding.build(p.map, enc.n_parts, "discrete").decode(x)
    assert np.allclose(d[:, 1:-1] % 1.0, 0.5)  # cell centres


def test_initial_population_and_mutation_keep_validity():
    p = GridPathProblem(GridPathConfig(map="seed20", m=1.05))
    rng = np.random.default_rng(1)
    x = p.operators.initial_population(60, rng)
    assert polyline_segments_valid(p.map.blocked, p.decode(x), "closed").all()
    y = p.operators.mutate(x, rng, 1.0)
    changed = (y != x).sum(axis=1)
    assert changed.max() == 1 and changed.sum() > 30  # one point, most rows changed
    assert polyline_segments_valid(p.map.blocked, p.decode(y), "closed").all()
    assert np.array_equal(p.operators.mutate(x, rng, 0.0), x)


def test_fitness_is_length_plus_penalty():
    p = GridPathProblem(GridPathConfig(map="seed10a", m=1.2))
    rng = np.random.default_rng(2)
    x = np.concatenate([p.operators.initial_population(5, rng),
                        p.genome.sample(rng, 20)])
    ev = p.evaluate(x)
    pts = p.decode(x)
    length = np.hypot(*np.diff(pts, axis=1).transpose(2, 0, 1)).sum(1)
    bad = (~polyline_segments_valid(p.map.blocked, pts, "closed")).sum(1)
    assert p.penalty == 20.0 and bad.max() > 0
    assert np.allclose(ev.fitness, length + 20.0 * bad)
    assert np.allclose(ev.metrics["length"], length)


def test_encoding_optimum_is_reachable_and_bounded():
    p = GridPathProblem(GridPathConfig(map="seed10a", m=1.2))
    lo, hi, count = p.operators.lo, p.operators.hi, p.operators.count
    layers = [np.unique(p.enc.snap(p.enc.foot_points()[g] + (0.5 * (lo[g, :c] + hi[g, :c]))
                                   [:, None] * p.enc.normal), axis=0)
              for g, c in enumerate(count)]
    best, pts = encoding_optimum(p.map.blocked, p.enc.start, p.enc.goal, layers, "closed")
    assert best == pytest.approx(np.hypot(*np.diff(pts, axis=0).T).sum())
    genes = p.enc.to_genes(pts[1:-1]).reshape(1, -1)  # cell centres lie in their cells
    assert p.evaluate(genes).fitness[0] == pytest.approx(best)


@pytest.mark.parametrize("spec", ["seed20", "random:14:0.3:2"])
def test_segment_tables_match_geometry(spec):
    p = GridPathProblem(GridPathConfig(map=spec, m=1.05))
    assert p.tables is not None
    rng = np.random.default_rng(3)
    x = np.concatenate([p.operators.initial_population(50, rng), p.genome.sample(rng, 150)])
    pts = p.decode(x)
    valid, length = p.tables.polylines(pts)
    assert np.array_equal(valid, polyline_segments_valid(p.map.blocked, pts, "closed"))
    assert np.allclose(length, np.hypot(*np.diff(pts, axis=1).transpose(2, 0, 1)))
    assert not valid.all()  # the random genomes do cross obstacles


@pytest.mark.parametrize("spec", ["seed20", "random:14:0.3:2"])
def test_lookup_fast_paths_equal_the_geometry(spec):
    """Fitness from gene-level lookups and the lookup-only mutation give exactly what the
    decoded points and the geometric segment test give."""
    p = GridPathProblem(GridPathConfig(map=spec, m=1.05))
    ops = p.operators
    assert ops.piece_cell is not None
    geo = PathOperators(p.enc, p.map.blocked, p.rule, retries=p.cfg.retries)
    rng = np.random.default_rng(5)
    x = np.concatenate([ops.initial_population(60, rng), p.genome.sample(rng, 60)])
    ev = p.evaluate(x)
    pts = p.decode(x)
    seg = np.hypot(*np.diff(pts, axis=1).transpose(2, 0, 1))
    bad = (~polyline_segments_valid(p.map.blocked, pts, "closed")).sum(1)
    assert np.array_equal(ev.fitness, seg.sum(1) + p.penalty * bad)
    for seed in range(3):
        fast = ops.mutate(x, np.random.default_rng(seed), 0.7)
        assert np.array_equal(fast, geo.mutate(x, np.random.default_rng(seed), 0.7))
        assert (fast != x).any()
