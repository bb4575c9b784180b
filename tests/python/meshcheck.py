"""Small numpy checks shared by the mesh tests (imported by the test modules beside it)."""

from __future__ import annotations

import numpy as np


def edges_closed(faces: np.ndarray) -> bool:
    """Every directed edge appears once and its reverse once: closed and consistently oriented."""
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]).astype(np.int64)
    n = int(faces.max()) + 1
    key, rev = e[:, 0] * n + e[:, 1], e[:, 1] * n + e[:, 0]
    return len(np.unique(key)) == len(key) and np.array_equal(np.sort(key), np.sort(rev))
