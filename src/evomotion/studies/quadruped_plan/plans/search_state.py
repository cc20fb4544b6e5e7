"""A walking search's :class:`~evomotion.core.search.SearchState` as npz arrays + JSON and
back, for checkpoints.

Duplicate keys are ints of up to 440 bits (:data:`.rules.KEY_BITS` x 11 fields), stored as 56
little-endian bytes each; parents and heap entries refer to nodes by index. Every float is a
float64 (exact round trip), the node and heap orders are kept, so a restored search expands
exactly what the original would have.
"""

from __future__ import annotations

from typing import Any, cast

import numpy as np

from evomotion.core.search import BestFirstSearch, Node

KEY_BYTES = 56


def search_to_arrays(search: BestFirstSearch) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    s = search.state
    keys = list(s.nodes)
    index = {k: i for i, k in enumerate(keys)}
    recs = list(s.nodes.values())
    n = len(keys)
    # a walking search's keys are ints (see the module doc)
    kb = np.frombuffer(b"".join(cast(int, k).to_bytes(KEY_BYTES, "little") for k in keys),
                       np.uint8)
    arrays = {
        "keys": kb.reshape(n, KEY_BYTES),
        "f": np.array([r.f for r in recs], float),
        "g": np.array([r.g for r in recs], float),
        "states": np.array([r.state[:11] for r in recs], float).reshape(n, 11),
        "parent": np.array([-1 if r.parent is None else index[r.parent] for r in recs],
                           np.int64),
        "rule": np.array([-1 if r.rule is None else r.rule for r in recs], np.int64),
        "closed": np.array([k in s.closed for k in keys], bool),
        "step_cost": np.array([r.step_cost for r in recs], float),
        "heap_f": np.array([e[0] for e in s.open], float),
        "heap_goal": np.array([e[1] for e in s.open], np.int64),
        "heap_counter": np.array([e[2] for e in s.open], np.int64),
        "heap_node": np.array([index[e[3]] for e in s.open], np.int64),
    }
    meta = {"counter": s.counter, "expansions": s.expansions, "generated": s.generated,
            "reopened": s.reopened, "reason": s.reason, "last_f": s.last_f,
            "seconds": s.seconds,
            "goal": None if s.goal_key is None else index[s.goal_key]}
    return arrays, meta


def search_from_arrays(search: BestFirstSearch, a: dict[str, np.ndarray],
                       meta: dict[str, Any]) -> BestFirstSearch:
    """Fill the fresh ``search`` (same problem and evaluation) from a checkpoint."""
    kb = np.asarray(a["keys"], np.uint8)
    keys = [int.from_bytes(row.tobytes(), "little") for row in kb]
    states = a["states"].tolist()
    parent, rule = a["parent"].tolist(), a["rule"].tolist()
    f, g, closed, cost = a["f"].tolist(), a["g"].tolist(), a["closed"].tolist(), \
        a["step_cost"].tolist()
    s = search.state
    s.nodes = {k: Node(f[i], g[i], (*states[i], k), None if parent[i] < 0 else keys[parent[i]],
                       None if rule[i] < 0 else rule[i], cost[i]) for i, k in enumerate(keys)}
    s.closed = {k for k, c in zip(keys, closed, strict=True) if c}
    s.open = [(hf, hg, hc, keys[hn]) for hf, hg, hc, hn in zip(
        a["heap_f"].tolist(), a["heap_goal"].tolist(), a["heap_counter"].tolist(),
        a["heap_node"].tolist(), strict=True)]
    s.counter, s.expansions = int(meta["counter"]), int(meta["expansions"])
    s.generated, s.reopened = int(meta["generated"]), int(meta["reopened"])
    s.reason, s.last_f = meta["reason"], float(meta["last_f"])
    s.seconds = float(meta["seconds"])
    s.goal_key = None if meta["goal"] is None else keys[int(meta["goal"])]
    return search
