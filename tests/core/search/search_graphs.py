"""Explicit graphs for the tests of the core search."""

from __future__ import annotations

import heapq
import math


class Graph:
    """Explicit weighted digraph: edges[u] = [(v, cost), ...]; states are ints."""

    def __init__(self, edges: dict[int, list[tuple[int, float]]], start: int, goals: set[int]):
        self.edges, self.s0, self.goals = edges, start, goals

    def start(self) -> int:
        return self.s0

    def is_goal(self, s: int) -> bool:
        return s in self.goals

    def successors(self, s: int) -> list[tuple[str, int, float]]:
        return [(f"{s}->{v}", v, c) for v, c in self.edges.get(s, [])]

    def key(self, s: int) -> int:
        return s


def dijkstra(g: Graph) -> float:
    dist = {g.s0: 0.0}
    heap = [(0.0, g.s0)]
    while heap:
        d, u = heapq.heappop(heap)
        if u in g.goals:
            return d
        if d > dist[u]:
            continue
        for v, c in g.edges.get(u, []):
            if d + c < dist.get(v, math.inf):
                dist[v] = d + c
                heapq.heappush(heap, (d + c, v))
    return math.inf


def zero(_s: object) -> float:
    return 0.0
