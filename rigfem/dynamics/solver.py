"""Joint reactions and driver torque of a planar linkage over a crank turn.

The linkage layer moves the linkage (:func:`rigfem.linkage.state.linkage_state`: the closed
forms of the rig's toggle-free four-bar and slider-crank, the general planar solver otherwise)
and hands its whole motion over as a :class:`~rigfem.linkage.model.LinkageState`; here the
bodies' loads (:mod:`rigfem.dynamics.forces`) are balanced on it, in closed form
(:mod:`rigfem.dynamics.closed`) or by the general inverse dynamics (:mod:`rigfem.dynamics.inverse`).
The public interface is in mm, N, N·m, degrees (see ``rigfem.dynamics.history``).
"""

from __future__ import annotations

import warnings

import numpy as np

from rigfem.dynamics.closed import closed_reactions
from rigfem.dynamics.forces import body_loads
from rigfem.dynamics.history import ReactionHistory
from rigfem.dynamics.inverse import general_reactions
from rigfem.linkage.closed import closed_motion
from rigfem.linkage.general import general_motion
from rigfem.linkage.model import Linkage, LinkageState
from rigfem.linkage.state import linkage_state

__all__ = ["solve", "reactions"]


def solve(lk: Linkage, crank_deg: np.ndarray, speed_hz: float = 1.0, *, general: bool = False,
          **deprecated) -> ReactionHistory:
    """Positions, velocities, accelerations and reactions at the driver phases ``crank_deg``.

    A toggle-free rig four-bar or slider-crank is solved in closed form
    (``rigfem.dynamics.closed``, ``meta["solver"] = "closed form"``); ``general=True`` forces
    the general solver (the reference the closed forms are tested against).

    ``crank_deg`` must be increasing (an evenly spaced full turn for a crank); the driver
    turns at ``speed_hz`` (negative = clockwise).  Returns a ReactionHistory whose
    ``singular_mask`` flags toggle samples and whose ``evaluator`` re-solves at any angle.

    ``tol_mm`` and ``check_closure`` (the general solver's, which no caller changed) are
    deprecated: given, they warn, and apply where the general solver runs (not where a closed form
    does); they go in rigfem 0.3.
    """
    deg = np.asarray(crank_deg, float)
    if deprecated:
        unknown = sorted(set(deprecated) - {"tol_mm", "check_closure"})
        if unknown:
            raise TypeError(f"solve() got an unexpected keyword argument {unknown[0]!r}")
        given = ", ".join(f"{k}=..." for k in deprecated)
        warnings.warn(f"solve({given}) is deprecated: no caller changes the general solver's tolerance or "
                      "closure check; the argument goes in rigfem 0.3", DeprecationWarning, stacklevel=2)
        motion = None if general else closed_motion(lk, np.radians(deg), 2 * np.pi * speed_hz)
        if motion is None:  # linkage_state's choice, with the general solver's deprecated options
            motion = general_motion(lk, deg, speed_hz, **deprecated)
        return reactions(lk, motion, deg, speed_hz)
    return reactions(lk, linkage_state(lk, deg, speed_hz, general=general), deg, speed_hz)


def reactions(lk: Linkage, motion: LinkageState, crank_deg: np.ndarray, speed_hz: float = 1.0) -> ReactionHistory:
    """The reactions of :func:`solve` on ``lk``'s ``motion`` at ``crank_deg``, as the linkage layer
    gave it; the evaluator re-solves on the same branch (``motion.at``) at any angle."""
    def evaluator(angles: np.ndarray) -> ReactionHistory:
        a = np.atleast_1d(np.asarray(angles, float))
        return reactions(lk, motion.at(a), a, speed_hz)

    deg = np.asarray(crank_deg, float)
    loads = body_loads(lk, motion)
    probe = None if motion.probe is None else (motion.probe, body_loads(lk, motion.probe))
    if motion.general is None:
        h = closed_reactions(lk, motion, loads, deg, speed_hz)
    else:
        h = general_reactions(lk, motion, loads, deg, speed_hz, probe)
    h.evaluator = evaluator
    return h
