"""Best-first search with OPEN/CLOSED and re-parenting, A*, weighted A*, budgets."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st
from search_graphs import Graph, dijkstra, zero

from evomotion.core.search import (
    EXPANSION_BUDGET,
    FOUND,
    OPEN_EMPTY,
    TIME_BUDGET,
    astar,
    best_first,
)


def test_astar_finds_least_cost_path_and_traces_it() -> None:
    g = Graph({0: [(1, 1.0), (2, 4.0)], 1: [(2, 1.0), (3, 5.0)], 2: [(3, 1.0)]}, 0, {3})
    r = astar(g, zero)
    assert r.stop_reason == FOUND and r.found
    assert r.states == [0, 1, 2, 3] and r.cost == 3.0
    assert r.rules == [None, "0->1", "1->2", "2->3"]
    assert "3 states" not in r.message and "4 states" in r.message


def test_reparenting_reopens_closed_state_with_inconsistent_heuristic() -> None:
    # h admissible but inconsistent: node 2 is closed via the expensive edge first
    g = Graph({0: [(1, 1.0), (2, 3.0)], 1: [(2, 1.0)], 2: [(3, 3.0)]}, 0, {3})
    h = {0: 0.0, 1: 3.0, 2: 0.0, 3: 0.0}
    r = astar(g, h.__getitem__)
    assert r.found and r.cost == 5.0 and r.states == [0, 1, 2, 3]
    assert r.reopened >= 1


def test_open_empty_when_goal_unreachable() -> None:
    g = Graph({0: [(1, 1.0)], 1: [(0, 1.0)]}, 0, {5})
    r = astar(g, zero)
    assert r.stop_reason == OPEN_EMPTY and not r.found
    assert "unreachable" in r.message and r.expansions == 2


def test_budgets_stop_with_reason() -> None:
    chain = Graph({i: [(i + 1, 1.0)] for i in range(1000)}, 0, {1000})
    r = astar(chain, zero, max_expansions=0)
    assert r.stop_reason == EXPANSION_BUDGET and r.expansions == 0
    assert "expansion budget" in r.message
    r = astar(chain, zero, max_expansions=10)
    assert r.stop_reason == EXPANSION_BUDGET and r.expansions == 10
    r = astar(chain, zero, max_seconds=0.0)
    assert r.stop_reason == TIME_BUDGET and "time budget" in r.message


def test_ties_prefer_goal_state() -> None:
    # 1 and 2 both have f = 1; 2 is the goal and is generated after 1
    g = Graph({0: [(1, 1.0), (2, 1.0)], 1: [(3, 1.0)]}, 0, {2})
    r = best_first(g, lambda pf, pg, ps, c, rule, cost: 0.0 if ps is None else 1.0)
    assert r.states == [0, 2] and r.expansions == 2


def test_no_parent_cycle_when_values_fall_along_a_cycle() -> None:
    # f keeps decreasing around the cycle 0 -> 1 -> 0: re-parenting 0 under 1 would loop
    g = Graph({0: [(1, 1.0)], 1: [(0, 1.0), (2, 1.0)]}, 0, {2})
    calls = iter(range(100, 0, -1))
    r = best_first(g, lambda *a: float(next(calls)))
    assert r.found and r.states[0] == 0 and r.states[-1] == 2


graphs = st.integers(3, 12).flatmap(lambda n: st.tuples(
    st.just(n),
    st.lists(st.tuples(st.integers(0, n - 1), st.integers(0, n - 1),
                       st.floats(0.1, 10.0)), min_size=1, max_size=4 * n)))


@settings(max_examples=60, deadline=None)
@given(graphs, st.floats(1.0, 4.0))
def test_astar_optimal_and_weighted_bounded(data: tuple, w: float) -> None:
    n, edge_list = data
    edges: dict[int, list[tuple[int, float]]] = {}
    for u, v, c in edge_list:
        edges.setdefault(u, []).append((v, c))
    g = Graph(edges, 0, {n - 1})
    best = dijkstra(g)
    r = astar(g, zero)
    if math.isinf(best):
        assert r.stop_reason == OPEN_EMPTY
        return
    assert r.found and math.isclose(r.cost, best, rel_tol=1e-9, abs_tol=1e-9)
    # the traced plan is a real path whose cheapest edges add up to the reported cost
    path_cost = sum(min(c for x, c in edges[u] if x == v)
                    for u, v in zip(r.states, r.states[1:], strict=False))
    assert math.isclose(path_cost, r.cost, rel_tol=1e-9, abs_tol=1e-9)
    # weighted A* with an admissible h (here the exact one scaled down) is within w
    rw = astar(g, lambda s: 0.5 * (0.0 if s == n - 1 else min(c for _, _, c in edge_list)),
               weight=w)
    assert rw.found and rw.cost <= w * best + 1e-9


@settings(max_examples=60, deadline=None)
@given(graphs, st.floats(1.0, 4.0), st.integers(0, 6))
def test_astar_lower_bound_never_exceeds_least_cost(data: tuple, w: float, budget: int) -> None:
    n, edge_list = data
    edges: dict[int, list[tuple[int, float]]] = {}
    for u, v, c in edge_list:
        edges.setdefault(u, []).append((v, c))
    g = Graph(edges, 0, {n - 1})
    best = dijkstra(g)
    cheapest = min(c for _, _, c in edge_list)
    r = astar(g, lambda s: 0.0 if s == n - 1 else cheapest, weight=w, max_expansions=budget)
    if r.found:
        assert r.lower_bound == r.cost / w and r.lower_bound <= best + 1e-9
    elif r.stop_reason == EXPANSION_BUDGET:
        assert r.lower_bound <= best + 1e-9 and "least cost >=" in r.message
    else:
        assert math.isnan(r.lower_bound) and math.isinf(best)
