"""Search the paper-like maps bundled with the grid-path study (run once; prints .map text).

The paper's own maps exist only as figures, so we look for random block maps on which
(1) octile A* gives exactly the paper's optimum (n_straight, n_diagonal) and (2) the paper's
perpendicular encoding with its m can express a path at least that short. (We also tried
to make the centres optimum equal the octile one, as the paper's figures suggest: in
thousands of random block, wall and cell maps with the right octile optimum, straight
centre-to-centre segments were always shorter, by 0.5-1.1 cells on 10x10.)

    python benchmarks/grid_path_paper_maps.py 10 4 7 1.2 --seed 0
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from evomotion.studies.grid_path.encoding import PerpendicularEncoding, parts_from_m
from evomotion.studies.grid_path.maps import GridMap, connected, write_map
from evomotion.studies.grid_path.operators import free_pieces
from evomotion.studies.grid_path.solvers import centres_optimum, encoding_optimum, octile_astar


def layers(m: GridMap, m_factor: float) -> list[np.ndarray]:
    L = float(np.hypot(*(m.goal_xy - m.start_xy)))
    enc = PerpendicularEncoding.build(m, parts_from_m(L, m_factor), "discrete")
    lo, hi, c = free_pieces(enc, m.blocked)
    out = []
    for g in range(enc.dim):
        y = 0.5 * (lo[g, :c[g]] + hi[g, :c[g]])
        out.append(np.unique(enc.snap(enc.foot_points()[g] + y[:, None] * enc.normal), axis=0))
    return out


def block_map(size: int, n_blocks: int, rng: np.random.Generator) -> np.ndarray:
    b = np.zeros((size, size), dtype=bool)
    for _ in range(n_blocks):
        w, h = rng.integers(1, 4, 2)
        x, y = rng.integers(0, size - w + 1), rng.integers(0, size - h + 1)
        b[y:y + h, x:x + w] = True
    b[0, 0] = b[-1, -1] = False
    return b


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("size", type=int)
    ap.add_argument("n_straight", type=int)
    ap.add_argument("n_diagonal", type=int)
    ap.add_argument("m", type=float)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--tries", type=int, default=20000)
    ap.add_argument("--out", default="")
    a = ap.parse_args()
    rng = np.random.default_rng(a.seed)
    s = a.size
    for i in range(a.tries):
        b = block_map(s, int(rng.integers(s // 2, s + 2)), rng)
        if not connected(b, (0, 0), (s - 1, s - 1)):
            continue
        m = GridMap(b, (0, 0), (s - 1, s - 1))
        o = octile_astar(m)
        if (o.n_straight, o.n_diagonal) != (a.n_straight, a.n_diagonal):
            continue
        e, _ = encoding_optimum(b, m.start_xy, m.goal_xy, layers(m, a.m), "closed")
        if e > o.length + 1e-9:
            continue
        c = centres_optimum(m, o.length)
        print(f"found after {i + 1} tries: octile {o.length:.4f}, centres {c.length:.4f}, "
              f"encoding {e:.4f}, density {b.mean():.2f}", file=sys.stderr)
        if a.out:
            write_map(a.out, b)
        return
    sys.exit("not found")


if __name__ == "__main__":
    main()
