"""A linkage's whole motion at given driver phases in one call: the closed forms where they
apply (:mod:`rigfem.linkage.closed`, the rig's toggle-free four-bar and slider-crank), the
general planar solver otherwise (:mod:`rigfem.linkage.general`).  ``rigfem check`` asks here
once, in its scene stage, and hands the :class:`~rigfem.linkage.model.LinkageState` to the
dynamics, which balances its forces on it (and on its ``at`` for other phases).
"""

from __future__ import annotations

import numpy as np

from rigfem.linkage.closed import closed_motion
from rigfem.linkage.general import general_motion
from rigfem.linkage.model import Linkage, LinkageState

__all__ = ["linkage_state"]


def linkage_state(lk: Linkage, crank_deg: np.ndarray, speed_hz: float = 1.0, *, general: bool = False) -> LinkageState:
    """``lk``'s motion at the increasing driver phases ``crank_deg`` (deg), the driver at
    ``speed_hz``; ``general=True`` forces the general solver (the closed forms' reference)."""
    deg = np.asarray(crank_deg, float)
    fast = None if general else closed_motion(lk, np.radians(deg), 2 * np.pi * speed_hz)
    return fast if fast is not None else general_motion(lk, deg, speed_hz)
