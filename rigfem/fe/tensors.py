"""Stress tensor invariants: von Mises and principal stresses (no FE machinery, so the verdict can use them cheaply)."""

from __future__ import annotations

import numpy as np


def von_mises(s: np.ndarray) -> np.ndarray:
    """Von Mises stress of Voigt tensors (..., 6)."""
    xx, yy, zz, xy, yz, xz = np.moveaxis(s, -1, 0)
    return np.sqrt(np.maximum(0.5 * ((xx - yy) ** 2 + (yy - zz) ** 2 + (zz - xx) ** 2)
                              + 3 * (xy ** 2 + yz ** 2 + xz ** 2), 0.0))


def principal(s: np.ndarray) -> np.ndarray:
    """Principal stresses (..., 3), descending, of Voigt tensors (..., 6)."""
    xx, yy, zz, xy, yz, xz = np.moveaxis(s, -1, 0)
    T = np.stack([np.stack([xx, xy, xz], -1), np.stack([xy, yy, yz], -1), np.stack([xz, yz, zz], -1)], -2)
    return np.linalg.eigvalsh(T)[..., ::-1]
