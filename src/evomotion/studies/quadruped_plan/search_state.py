"""A :class:`~.walk_search.WalkSearch` as npz arrays + JSON and back, for checkpoints.

Duplicate keys are ints of up to 440 bits (:data:`.rules.KEY_BITS` x 11 fields), stored as 56
little-endian bytes each; parents and heap entries refer to nodes by index. Every float is a
float64 (exact round trip), the node and heap orders are kept, so a restored search expands
exactly what the original would have.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from evomotion.studies.quadruped_plan.walk_search import WalkSearch

KEY_BYTES = 56


def search_to_arrays(s: WalkSearch) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    keys = list(s.nodes)
    index = {k: i for i, k in enumerate(keys)}
    recs = list(s.nodes.values())
    n = len(keys)
    kb = np.frombuffer(b"".join(k.to_bytes(KEY_BYTES, "little") for k in keys), np.uint8)
    arrays = {
        "keys": kb.reshape(n, KEY_BYTES),
        "f": np.array([r[0] for r in recs], float),
        "g": np.array([r[1] for r in recs], float),
        "states": np.array([r[2][:11] for r in recs], float).reshape(n, 11),
        "parent": np.array([-1 if r[3] is None else index[r[3]] for r in recs], np.int64),
        "rule": np.array([-1 if r[4] is None else r[4] for r in recs], np.int64),
        "closed": np.array([r[5] for r in recs], bool),
        "step_cost": np.array([r[6] for r in recs], float),
        "heap_f": np.array([e[0] for e in s.heap], float),
        "heap_goal": np.array([e[1] for e in s.heap], np.int64),
        "heap_counter": np.array([e[2] for e in s.heap], np.int64),
        "heap_node": np.array([index[e[3]] for e in s.heap], np.int64),
    }
    meta = {"counter": s.counter, "expansions": s.expansions, "generated": s.generated,
            "reopened": s.reopened, "reason": s.reason, "last_f": s.last_f,
            "seconds": s.seconds,
            "goal": None if s.goal_key is None else index[s.goal_key]}
    return arrays, meta


def search_from_arrays(search: WalkSearch, a: dict[str, np.ndarray],
                       meta: dict[str, Any]) -> WalkSearch:
    """Fill the fresh ``search`` (same problem and evaluation) from a checkpoint."""
    kb = np.asarray(a["keys"], np.uint8)
    keys = [int.from_bytes(row.tobytes(), "little") for row in kb]
    states = a["states"].tolist()
    parent, rule = a["parent"].tolist(), a["rule"].tolist()
    f, g, closed, cost = a["f"].tolist(), a["g"].tolist(), a["closed"].tolist(), \
        a["step_cost"].tolist()
    search.nodes = {k: [f[i], g[i], (*states[i], k), None if parent[i] < 0 else keys[parent[i]],
                        None if rule[i] < 0 else rule[i], bool(closed[i]), cost[i]]
                    for i, k in enumerate(keys)}
    search.heap = [(hf, hg, hc, keys[hn]) for hf, hg, hc, hn in zip(
        a["heap_f"].tolist(), a["heap_goal"].tolist(), a["heap_counter"].tolist(),
        a["heap_node"].tolist(), strict=True)]
    search.counter, search.expansions = int(meta["counter"]), int(meta["expansions"])
    search.generated, search.reopened = int(meta["generated"]), int(meta["reopened"])
    search.reason, search.last_f = meta["reason"], float(meta["last_f"])
    search.seconds = float(meta["seconds"])
    search.goal_key = None if meta["goal"] is None else keys[int(meta["goal"])]
    return search
