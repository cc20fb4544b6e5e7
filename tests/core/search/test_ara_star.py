"""ARA* (Likhachev, Gordon & Thrun 2003) over the core search."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st
from search_graphs import Graph, dijkstra

from evomotion.core.search import FOUND, AraStar, ara_star, astar_evaluation


def _graph(n: int, edge_list: list) -> Graph:
    edges: dict[int, list[tuple[int, float]]] = {}
    for u, v, c in edge_list:
        edges.setdefault(u, []).append((v, float(c)))
    return Graph(edges, 0, {n - 1})


graphs = st.integers(3, 12).flatmap(lambda n: st.tuples(
    st.just(n), st.lists(st.tuples(st.integers(0, n - 1), st.integers(0, n - 1),
                                   st.integers(1, 5)), min_size=1, max_size=4 * n)))


@settings(max_examples=60, deadline=None)
@given(graphs)
def test_ara_star_ends_optimal_with_every_bound_holding(data: tuple) -> None:
    n, edge_list = data
    g = _graph(n, edge_list)
    best = dijkstra(g)
    res = ara_star(g, lambda s: 0.0 if s == n - 1 else 1.0)  # consistent: every edge >= 1
    if math.isinf(best):
        assert not res.states
        return
    assert res.cost == best and res.bound == 1.0
    for it in res.iterations:
        assert it.reason == FOUND and it.cost <= it.bound * best + 1e-9 <= it.weight * best + 1e-9


def test_iterations_reuse_the_search() -> None:
    edges = {i: [(i + 1, 1.0), (i + 2, 2.5)] for i in range(30)}
    g = Graph(edges, 0, {30})
    ara = AraStar(g, lambda w: (astar_evaluation(lambda s: (30 - s) / 2.5, w), None),
                  (3.0, 1.0))
    first = ara.improve(10_000)
    spent = ara.search.state.expansions
    second = ara.improve(10_000)
    assert first.reason == second.reason == FOUND and ara.done
    assert second.cost == 30.0 and second.bound == 1.0 and first.cost >= second.cost
    assert ara.search.state.expansions - spent < 31  # it did not start over
