"""One crank turn's reaction history, what the stress checker calls: the rigid-body model
(``rigfem.dynamics.solver``) or the 2013 program (``rigfem.dynamics.original``).

Mass models (geometry/RIG.md §3): ``"rigid-body"`` (default) — the bodies' mass data as the catalogue
builds it (:mod:`rigfem.linkage.mechanisms`); ``"original"`` — the 2013 program (four-bar
only), with the study's rail mass and its pivot at the guide's end.
"""

from __future__ import annotations

import numpy as np

from rigfem.dynamics.history import DynamicsOptions, ReactionHistory, Reactions, reactions_of
from rigfem.dynamics.original import simulate_original
from rigfem.dynamics.solver import reactions
from rigfem.dynamics.inputs import linkage_of
from rigfem.errors import ComputeError
from rigfem.linkage.mechanisms import crank_angles
from rigfem.linkage.model import Linkage, LinkageState
from rigfem.linkage.state import linkage_state
from rigfem.settings import MODELS, check_mass_model

__all__ = ["MODELS", "simulate", "cycle_history", "react"]


def simulate(linkage_or_config: Linkage | dict, samples: int = 360, speed_hz: float = 1.0,
             model: str = "rigid-body") -> ReactionHistory:
    """Reaction history of one constant-speed crank turn (N, N·m, mm, deg).

    ``linkage_or_config`` is a Linkage or a dict ``{"type": "four-bar", "b2": .., ...}``
    (builder keyword arguments).  ``model="original"`` (four-bar only) reproduces the 2013
    program; ``"rigid-body"`` is the physically consistent default.  ``meta["singular"]``
    lists the toggle crank-angle ranges (None if none); ``meta["mu_deg"]`` the
    transmission-angle range of a four-bar.
    """
    DynamicsOptions(samples, model, speed_hz)  # checks them (a value type): a script calls this
    lk = linkage_of(linkage_or_config) if isinstance(linkage_or_config, dict) else linkage_or_config
    check_mass_model(model, lk.meta)
    deg = crank_angles(int(samples))
    return cycle_history(lk, linkage_state(lk, deg, speed_hz), deg, speed_hz, model)


def cycle_history(lk: Linkage, motion: LinkageState, deg: np.ndarray, speed_hz: float,
                  model: str = "rigid-body") -> ReactionHistory:
    """The reaction history of :func:`simulate` on ``lk``'s ``motion`` at the crank angles ``deg``,
    as the linkage layer gave it (:func:`rigfem.linkage.state.linkage_state`)."""
    if model != "original":
        h = reactions(lk, motion, deg, speed_hz)
        h.meta["model"] = "rigid-body"
        if motion.mu_deg is not None:
            h.meta["mu_deg"] = dict(min=float(motion.mu_deg.min()), max=float(motion.mu_deg.max()))
        return h
    if lk.meta.get("type") != "four-bar" or lk.meta.get("masses") != "rig":  # check_mass_model refuses it
        raise ComputeError(f"model 'original' exists only for the four-bar with the rig masses, "
                           f"not {lk.meta.get('type')!r} with masses {lk.meta.get('masses')!r}")
    return simulate_original(lk, motion, deg, speed_hz)


def react(lk: Linkage, motion: LinkageState, options: DynamicsOptions) -> Reactions:
    """The reactions stage of a check: the linkage's reaction history over the turn its ``motion``
    covers (``options.samples`` crank angles), with its peaks and summary."""
    return reactions_of(cycle_history(lk, motion, crank_angles(options.samples), options.speed_hz,
                                      options.mass_model))
