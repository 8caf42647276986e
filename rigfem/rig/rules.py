"""Rig rules (geometry/RIG.md §2): what makes a configuration buildable and acceptable.

Each rule is reported with its value, its limit and pass/fail, so a report can show
how far a configuration is from every limit.  Lengths in mm, angles in degrees.

One vocabulary for what a configuration is, in every output (:func:`standing`): it *assembles*
(closes over a full turn), it *meets the rig rules* (every rule below) and it *passes the stress
criterion* (every part's peak von Mises below σu/2) — three separate statements.
"""

from __future__ import annotations

import operator
from dataclasses import asdict, dataclass

import numpy as np

#: rail hole pitch (mm): bar lengths can only be set in these steps
HOLE_PITCH_MM = 60.0


#: the crank guide clears the rocker pivot only from this ground length (mm)
MIN_GROUND_MM = 660.0


#: acceptable transmission-angle band of the final design (deg)
MU_LIMITS_DEG = (35.0, 145.0)


#: the one vocabulary's three statements, each with its negation (see :func:`standing`)
ASSEMBLES = ("assembles", "does not assemble")
MEETS_RULES = ("meets the rig rules", "does not meet the rig rules")
STRESS = {"pass": "passes the stress criterion", "fail": "fails the stress criterion",
          "undecided": "undecided on the stress criterion (its error band contains the limit)"}


def standing(assembles: bool, meets_rules: bool | None, stress: str | None = None) -> str:
    """A configuration in the one vocabulary: ``assembles; meets the rig rules; passes the stress
    criterion`` (``meets_rules`` None: not a rig configuration; ``stress`` None: not computed)."""
    rules = "the rig rules do not apply" if meets_rules is None else MEETS_RULES[not meets_rules]
    return "; ".join([ASSEMBLES[not assembles], rules, STRESS.get(stress, "stress not computed")])


@dataclass
class Rule:
    """One rule: ``ok`` is ``value <relation> limit``."""

    name: str
    value: float
    limit: float
    ok: bool
    relation: str
    unit: str = "mm"

    def as_dict(self) -> dict:
        return asdict(self)


def _rule(name: str, value: float, relation: str, limit: float, unit: str = "mm") -> Rule:
    ok = {"<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge,
          "==": lambda a, b: abs(a - b) <= 1e-9}[relation](value, limit)
    return Rule(name, float(value), float(limit), bool(ok), relation, unit)


def transmission_angle_range(b2: float, b3: float, b4: float, d: float) -> tuple[float, float]:
    """(mu_min, mu_max) in degrees with the crank along the ground line (geometry/RIG.md §2).

    When the loop locks before reaching that position the cosine leaves [-1, 1] and the
    extreme is clipped to 0 or 180 deg (a toggle).
    """
    def mu(f):
        return float(np.degrees(np.arccos(np.clip((b3**2 + b4**2 - f**2) / (2 * b3 * b4), -1.0, 1.0))))

    return mu(d - b2), mu(d + b2)


#: the start of the hole-grid rule's name (formerly "mountable", a word the vocabulary no longer uses)
ON_HOLE_GRID = "on the hole grid"


def _on_hole_grid(lengths: dict[str, float]) -> Rule:
    """Largest distance (mm) of any length from a whole number of hole pitches; limit 0."""
    errs = {k: abs(v - HOLE_PITCH_MM * round(v / HOLE_PITCH_MM)) for k, v in lengths.items()}
    worst = max(errs, key=errs.get)
    off = f"; {worst} is off by {errs[worst]:g} mm" if errs[worst] > 1e-9 else ""
    return _rule(f"{ON_HOLE_GRID} (whole 60 mm hole pitches{off})", errs[worst], "==", 0.0)


def fourbar_rules(b2: float, b3: float, b4: float, d: float) -> list[Rule]:
    """The rig rules of a four-bar (crank b2, coupler b3, rocker b4, ground d; mm)."""
    mu_min, mu_max = transmission_angle_range(b2, b3, b4, d)
    return [
        _rule("loop can close (d < b2 + b3 + b4)", d, "<", b2 + b3 + b4),
        _rule("crank turns fully (b2 + d < b3 + b4)", b2 + d, "<", b3 + b4),
        _rule("crank guide clears the rocker pivot (d >= 660 mm)", d, ">=", MIN_GROUND_MM),
        _rule("transmission angle min (mu_min > 35 deg)", mu_min, ">", MU_LIMITS_DEG[0], "deg"),
        _rule("transmission angle max (mu_max < 145 deg)", mu_max, "<", MU_LIMITS_DEG[1], "deg"),
        _on_hole_grid(dict(b2=b2, b3=b3, b4=b4, d=d)),
    ]


def slider_crank_rules(b2: float, b3: float, offset: float = 0.0) -> list[Rule]:
    """The rig rules of a slider-crank (crank b2, rod b3, slide-line offset; mm)."""
    rules = [_rule("rod and crank cannot align (b2 < b3)", b2, "<", b3)]
    if offset:
        rules.append(_rule("crank turns fully with the offset (b2 + |offset| < b3)", b2 + abs(offset), "<", b3))
    rules.append(_on_hole_grid(dict(b2=b2, b3=b3)))
    return rules


def rules_for(meta: dict) -> list[Rule]:
    """Rules of a linkage from its ``meta`` (four-bar and slider-crank; others have none, nor
    has a textbook linkage, ``meta["textbook"]``, which is not a rig configuration)."""
    if meta.get("textbook"):
        return []
    L = meta.get("lengths_mm", {})
    if meta.get("type") == "four-bar":
        return fourbar_rules(L["b2"], L["b3"], L["b4"], L["d"])
    if meta.get("type") == "slider-crank":
        return slider_crank_rules(L["b2"], L["b3"], L.get("offset", 0.0))
    return []


def broken_rules(meta: dict) -> list[str]:
    """The rules of a linkage (its ``meta``) that it breaks, each with its numbers."""
    return [f"{r.name}: {r.value:.6g} {r.unit} must be {r.relation} {r.limit:.6g} {r.unit}"
            for r in rules_for(meta) if not r.ok]
