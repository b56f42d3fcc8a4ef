"""Random smooth shapes and affine maps for the georeferencing tests."""

from __future__ import annotations

import numpy as np


def blob(seed: int, n: int = 80) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = 1 + sum(rng.normal(0, 0.25 / k) * np.cos(k * t + rng.uniform(0, 6.3))
                for k in range(1, 6))
    return np.column_stack([r * np.cos(t), r * np.sin(t)])


def random_affine(rng: np.random.Generator) -> np.ndarray:
    a = rng.uniform(0, 2 * np.pi)
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    L = rng.uniform(0.5, 40) * R @ np.array([[1, rng.uniform(-0.5, 0.5)], [0, 1]]) @ np.diag(
        [rng.uniform(0.6, 1.4), 1.0])
    if rng.uniform() < 0.5:
        L = L @ np.diag([1.0, -1.0])
    return L
