"""The search's explicit state: runs in batches, copies of its state, lazy successors, ties."""

from __future__ import annotations

import copy
import math

from hypothesis import given, settings
from hypothesis import strategies as st
from search_graphs import Graph

from evomotion.core.search import (
    FOUND,
    BestFirstSearch,
    Node,
    SearchState,
    astar_evaluation,
    best_first,
    goal_first_deeper,
)


def grid(n: int) -> Graph:
    """An n x n 4-connected grid with unit costs, start 0, goal the far corner."""
    edges: dict[int, list[tuple[int, float]]] = {}
    for y in range(n):
        for x in range(n):
            u = y * n + x
            edges[u] = [(v, 1.0) for v, ok in ((u + 1, x + 1 < n), (u - 1, x > 0),
                                               (u + n, y + 1 < n), (u - n, y > 0)) if ok]
    return Graph(edges, 0, {n * n - 1})


def manhattan(n: int):
    return lambda s: float(abs(s % n - (n - 1)) + abs(s // n - (n - 1)))


def _summary(search: BestFirstSearch) -> tuple:
    r = search.result()
    return r.stop_reason, r.states, r.expansions, r.generated, r.reopened, r.cost


@settings(max_examples=30, deadline=None)
@given(st.integers(3, 9), st.lists(st.integers(1, 20), min_size=1, max_size=6))
def test_batches_and_state_copies_expand_what_one_run_does(n: int, batches: list[int]) -> None:
    ev = astar_evaluation(manhattan(n), 1.5)
    one = BestFirstSearch(grid(n), ev)
    one.run(10_000)
    stepped = BestFirstSearch(grid(n), ev)
    total = 0
    for b in batches * 50:
        total += b
        # a checkpoint is the plain-data state: resume from a deep copy of it
        stepped = BestFirstSearch(grid(n), ev, state=copy.deepcopy(stepped.state))
        if stepped.run(total) == FOUND:
            break
    stepped.run(10_000)
    assert _summary(stepped) == _summary(one)


def test_state_is_plain_typed_data() -> None:
    s = BestFirstSearch(grid(3), astar_evaluation(manhattan(3)))
    s.run(2)
    assert isinstance(s.state, SearchState)
    assert all(isinstance(node, Node) for node in s.state.nodes.values())
    assert s.state.closed == {0, 1}  # ties of f: the state generated first
    assert s.state.expansions == 2 and s.state.nodes[0].parent is None


class LazyChain(Graph):
    """The grid again, with the moves to the right as lazy successors."""

    def __init__(self, n: int) -> None:
        g = grid(n)
        self.n = n
        super().__init__({u: [(v, c) for v, c in es if v != u + 1] for u, es in g.edges.items()},
                         g.s0, g.goals)
        self.right = {u: any(v == u + 1 for v, _ in es) for u, es in g.edges.items()}

    def lazy_successors(self, s: int) -> list[tuple[str, int, float, int]]:
        return [(f"{s}->{s + 1}", s + 1, 1.0, s)] if self.right[s] and s + 1 not in self.goals \
            else []

    def successors(self, s: int) -> list[tuple[str, int, float]]:
        out = super().successors(s)
        if self.right[s] and s + 1 in self.goals:  # a goal is never a lazy child
            out.append((f"{s}->{s + 1}", s + 1, 1.0))
        return out

    def build(self, s: int, payload: int, key: int) -> int:
        return key


def test_lazy_successors_search_the_same_graph() -> None:
    h = manhattan(5)
    lazy = best_first(LazyChain(5), astar_evaluation(h))
    ev = astar_evaluation(h)
    quick = best_first(LazyChain(5), ev, lazy_evaluate=lambda pf, pg, ps, p, c: pg + c + h(p + 1))
    assert lazy.found and quick.found and lazy.cost == quick.cost == 8.0
    assert (lazy.states, lazy.expansions) == (quick.states, quick.expansions)


def test_deeper_ties_expand_fewer_states_on_a_plateau() -> None:
    ev = astar_evaluation(manhattan(8))
    fifo = best_first(grid(8), ev)
    deep = best_first(grid(8), ev, tie_break=goal_first_deeper)
    assert fifo.cost == deep.cost == 14.0
    assert deep.expansions < fifo.expansions and deep.expansions == 15


def test_unbounded_run_of_a_finished_search_returns_its_reason() -> None:
    s = BestFirstSearch(grid(3), astar_evaluation(manhattan(3)))
    assert s.run(math.inf) == FOUND == s.run(0)  # type: ignore[arg-type]
