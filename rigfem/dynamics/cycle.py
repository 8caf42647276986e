"""One crank turn's reaction history, what the stress checker calls: the rigid-body model
(``rigfem.dynamics.solver``) or the 2013 program (``rigfem.dynamics.original``).

Mass models (geometry/RIG.md §3): ``"rigid-body"`` (default) — the bodies' mass data as the catalogue
builds it (:mod:`rigfem.linkage.mechanisms`); ``"original"`` — the 2013 program (four-bar
only), with the study's rail mass and its pivot at the guide's end.
"""

from __future__ import annotations

import numpy as np

from rigfem.dynamics.history import BodyHistory, JointHistory, ReactionHistory, merge_ranges, singular_ranges
from rigfem.dynamics.original import original_reactions
from rigfem.dynamics.solver import reactions
from rigfem.errors import InputError
from rigfem.linkage.loops import MU_TOGGLE_DEG
from rigfem.linkage.mechanisms import BUILDERS, crank_angles, transmission_angle
from rigfem.linkage.model import GROUND, Linkage, LinkageState
from rigfem.linkage.state import linkage_state
from rigfem.rig.catalogue import RigMasses
from rigfem.settings import MODELS

__all__ = ["MODELS", "simulate", "cycle_history", "simulate_original"]


def simulate(linkage_or_config: Linkage | dict, samples: int = 360, speed_hz: float = 1.0,
             model: str = "rigid-body") -> ReactionHistory:
    """Reaction history of one constant-speed crank turn (N, N·m, mm, deg).

    ``linkage_or_config`` is a Linkage or a dict ``{"type": "four-bar", "b2": .., ...}``
    (builder keyword arguments).  ``model="original"`` (four-bar only) reproduces the 2013
    program; ``"rigid-body"`` is the physically consistent default.  ``meta["singular"]``
    lists the toggle crank-angle ranges (None if none); ``meta["mu_deg"]`` the
    transmission-angle range of a four-bar.
    """
    if model not in MODELS:
        raise InputError(f"model = {model!r} must be one of {', '.join(MODELS)}")
    if int(samples) != samples or not 8 <= samples <= 1_000_000:
        raise InputError(f"samples = {samples!r} must be a whole number in [8, 1000000]")
    if not np.isfinite(speed_hz) or speed_hz == 0 or abs(speed_hz) > 100:
        raise InputError(f"speed_hz = {speed_hz!r} must be non-zero and within [-100, 100] Hz")
    if isinstance(linkage_or_config, dict):
        cfg = dict(linkage_or_config)
        typ = cfg.pop("type", None)
        if typ not in BUILDERS:
            raise InputError(f"linkage type = {typ!r} must be one of {', '.join(BUILDERS)}")
        lk = BUILDERS[typ](**cfg)
    else:
        lk = linkage_or_config
    deg = crank_angles(int(samples))
    return cycle_history(lk, linkage_state(lk, deg, speed_hz), deg, speed_hz, model)


def cycle_history(lk: Linkage, motion: LinkageState, deg: np.ndarray, speed_hz: float,
                  model: str = "rigid-body") -> ReactionHistory:
    """The reaction history of :func:`simulate` on ``lk``'s ``motion`` at the crank angles ``deg``,
    as the linkage layer gave it (:func:`rigfem.linkage.state.linkage_state`)."""
    if model == "original":
        if lk.meta.get("type") != "four-bar" or lk.meta.get("masses") != "rig":
            raise InputError(f"model 'original' exists only for the four-bar with the rig masses, "
                             f"not {lk.meta.get('type')!r} with masses {lk.meta.get('masses')!r}")
        return simulate_original(lk, motion, deg, speed_hz)
    h = reactions(lk, motion, deg, speed_hz)
    h.meta["model"] = "rigid-body"
    if lk.meta.get("type") == "four-bar":
        mu = transmission_angle(h.bodies)
        h.meta["mu_deg"] = dict(min=float(mu.min()), max=float(mu.max()))
    return h


def simulate_original(lk: Linkage, motion: LinkageState, deg: np.ndarray, speed_hz: float) -> ReactionHistory:
    """ReactionHistory of the 2013 program (rigfem.dynamics.original) for a four-bar Linkage; its
    bodies' mass data from ``lk``'s ``motion`` at ``deg``."""
    L = lk.meta["lengths_mm"]
    b2, b3, b4, d = L["b2"], L["b3"], L["b4"], L["d"]
    sgn = 1 if lk.meta.get("branch", "open") == "open" else -1
    bodies_tpl = motion.histories

    def build(angles: np.ndarray, full_turn: bool = False) -> ReactionHistory:
        a = np.atleast_1d(np.asarray(angles, float))
        r = original_reactions(b2, b3, b4, d, np.radians(a), speed_hz, RigMasses(**lk.meta["catalogue"]),
                               tuple(lk.meta["rails_mm"]), branch=sgn)
        k = r["kin"]
        w2 = 2 * np.pi * speed_hz
        pos = {"O2": np.zeros((a.size, 2)), "A": k["A"] * 1000, "B": k["B"] * 1000,
               "O4": np.tile([d, 0.0], (a.size, 1))}
        joints = {"O2": JointHistory("O2", GROUND, "crank", r["R12"], pos["O2"]),
                  "A": JointHistory("A", "crank", "coupler", r["R23"], pos["A"]),
                  "B": JointHistory("B", "coupler", "rocker", r["R34"], pos["B"]),
                  "O4": JointHistory("O4", GROUND, "rocker", r["R14"], pos["O4"])}
        zero = np.zeros(a.size)
        aA = -(w2**2) * k["A"] * 1000
        bodies = {}
        for name, th, om, al, org, acc in (
                ("crank", k["theta2"], k["omega2"], zero, pos["O2"], np.zeros((a.size, 2))),
                ("coupler", k["theta3"], k["omega3"], k["alpha3"], pos["A"], aA),
                ("rocker", k["theta4"], k["omega4"], k["alpha4"], pos["O4"], np.zeros((a.size, 2)))):
            t = bodies_tpl[name]
            bodies[name] = BodyHistory(name, th, om, al, org, acc, t.mass_kg, t.com_local_mm,
                                       t.inertia_com_kg_mm2, t.point_masses, t.joint_local_mm)
        mu = r["mu_deg"]
        bad = np.sin(np.radians(mu)) < np.sin(np.radians(MU_TOGGLE_DEG))
        bad |= ~np.all(np.isfinite(np.c_[r["R12"], r["R23"], r["R34"], r["R14"], r["M2"]]), axis=1)
        meta = dict(lk.meta)
        meta.pop("singular_fn", None)
        meta.update(model="original", speed_hz=speed_hz, driver_unit="N·m",
                    mu_deg=dict(min=float(mu.min()), max=float(mu.max())),
                    singular=singular_ranges(a, bad))
        for j in joints.values():
            j.force_N = np.where(np.isfinite(j.force_N), j.force_N, 0.0)
        return ReactionHistory(a, joints, np.nan_to_num(r["M2"]), bodies, meta,
                               singular_mask=bad if bad.any() else None, full_turn=full_turn)

    h = build(deg, motion.full_turn)
    # toggles between the samples: the closed-form model is cheap on a 0.1 deg grid
    h.meta["singular"] = merge_ranges(h.meta["singular"], build(crank_angles(3600)).meta["singular"])
    h.evaluator = build
    return h
