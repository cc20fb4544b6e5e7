"""Neighbourhoods of a cellular GA on a toroidal 2D grid.

Shapes follow Alba & Dorronsoro, *Cellular Genetic Algorithms* (Springer 2008, ch. 1-2)
and Alba, Cotta & Troya (2000):

- ``L5``  linear 5 / Von Neumann: the cell and its 4 orthogonal neighbours;
- ``C9``  compact 9 / Moore: the 3x3 block;
- ``L9``  linear 9 / extended Von Neumann: up to two steps along each axis;
- ``C13`` compact 13: the 3x3 block plus two steps along each axis;
- ``Margolus``: the 2x2 block containing the cell, with the block partition shifted by
  (1, 1) on odd generations (Toffoli & Margolus 1987), so information crosses blocks.

A table ``idx[n_cells, k]`` lists, for every cell (row-major index), itself in column 0
and then its neighbours. All neighbourhoods are symmetric (b in N(a) iff a in N(b)).
"""

from __future__ import annotations

import numpy as np

_OFFSETS: dict[str, list[tuple[int, int]]] = {
    "L5": [(0, 0), (-1, 0), (1, 0), (0, -1), (0, 1)],
    "C9": [(0, 0)] + [(dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if (dr, dc) != (0, 0)],
    "L9": [(0, 0), (-1, 0), (1, 0), (0, -1), (0, 1), (-2, 0), (2, 0), (0, -2), (0, 2)],
}
_OFFSETS["C13"] = _OFFSETS["C9"] + [(-2, 0), (2, 0), (0, -2), (0, 2)]

NEIGHBOURHOODS: tuple[str, ...] = ("L5", "C9", "L9", "C13", "Margolus")


def grid_shape(pop_size: int, rows: int = 0) -> tuple[int, int]:
    """``(rows, cols)`` of the toroidal grid; ``rows=0`` picks the most square factorisation."""
    if pop_size < 1:
        raise ValueError(f"pop_size must be >= 1, got {pop_size}")
    if rows:
        if pop_size % rows:
            raise ValueError(f"pop_size {pop_size} is not a multiple of rows {rows}")
        return rows, pop_size // rows
    r = int(np.floor(np.sqrt(pop_size)))
    while pop_size % r:
        r -= 1
    return r, pop_size // r


def neighbour_table(name: str, rows: int, cols: int, generation: int = 0) -> np.ndarray:
    """``idx[rows*cols, k]``: column 0 is the cell itself, then its neighbours (toroidal).

    Only ``Margolus`` depends on ``generation`` (its parity picks the block partition).
    Offsets that wrap onto the same cell on tiny grids are kept (duplicates are harmless
    for selection and keep ``k`` fixed).
    """
    r, c = np.divmod(np.arange(rows * cols), cols)
    if name == "Margolus":
        s = generation % 2
        r0 = ((r - s) // 2) * 2 + s
        c0 = ((c - s) // 2) * 2 + s
        block = [(0, 0), (0, 1), (1, 0), (1, 1)]
        cells = np.stack([((r0 + dr) % rows) * cols + (c0 + dc) % cols for dr, dc in block], 1)
        if rows < 2 or cols < 2:
            raise ValueError("the Margolus neighbourhood needs a grid of at least 2x2")
        me = r * cols + c
        others = cells[cells != me[:, None]].reshape(-1, 3)
        return np.concatenate([me[:, None], others], axis=1)
    try:
        offs = _OFFSETS[name]
    except KeyError:
        from evomotion.core.registry import lookup

        lookup(dict.fromkeys(NEIGHBOURHOODS), "neighbourhood", name)
        raise
    return np.stack([((r + dr) % rows) * cols + (c + dc) % cols for dr, dc in offs], 1)
