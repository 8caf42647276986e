"""The rig sweep's parameters and the configurations it enumerates: every configuration on the
rig (each length on the hole grid within its rail) of a linkage type, with its rig rules
(:mod:`rigfem.sweep.run`).

Units: mm, Hz, deg.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import re
from dataclasses import dataclass

from rigfem.errors import InputError, check_range
from rigfem.rig.catalogue import RIG_RAILS_MM
from rigfem.rig.layout import RailLayout, rail_layout
from rigfem.rig.rules import HOLE_PITCH_MM, MIN_GROUND_MM, fourbar_rules, slider_crank_rules
from rigfem.schema import validate_check
from rigfem.settings import FIDELITY, MODELS, PLATE, RAIL, CheckSettings, check_settings

TYPES = ("four-bar", "slider-crank")


#: ground rail length (mm), geometry/RIG.md §3
GROUND_RAIL_MM = 2500.0


#: basis directions for bearing loads whose direction is set by the configuration (original mode)
ORIGINAL_DIRECTIONS = 72


#: candidate nodes of each unit field (its highest von Mises)
TOP_NODES = 30


#: groups of crank-angle rows, each with its own stress bound per node (see :func:`case_peak`)
BOUND_GROUPS = 36


#: crank-angle rows superposed at once
ROW_CHUNK = 24


#: joints whose peak reaction the table reports, per linkage type
JOINTS = {"four-bar": ("O2", "A", "B", "O4"), "slider-crank": ("O2", "A", "B", "slide")}


LENGTHS = {"four-bar": ("b2", "b3", "b4", "d"), "slider-crank": ("b2", "b3", "offset")}


@dataclass(frozen=True)
class SweepParams:
    """What a sweep computes; its hash keys the stored chunks."""

    linkage_type: str = "four-bar"
    speed_hz: float = 1.0
    model: str = "rigid-body"
    fidelity: str = "draft"
    samples: int = 360
    rails_mm: tuple[float, ...] = RIG_RAILS_MM
    ground_mm: float = GROUND_RAIL_MM
    check: tuple[tuple[str, object], ...] = ()  #: extra ``[check]`` fields (e.g. coarser test meshes)

    def __post_init__(self) -> None:
        if self.linkage_type not in TYPES:
            raise InputError(f"linkage type = {self.linkage_type!r} must be one of {', '.join(TYPES)}")
        if self.model not in MODELS:
            raise InputError(f"model = {self.model!r} must be one of {', '.join(MODELS)}")
        if self.model == "original" and self.linkage_type != "four-bar":
            raise InputError("model = 'original' exists only for the four-bar; use rigid-body")
        if self.fidelity not in FIDELITY:
            raise InputError(f"fidelity = {self.fidelity!r} must be one of {', '.join(FIDELITY)}")
        check_range("speed_hz", self.speed_hz, 0.0, 100.0, "Hz", lo_open=True)
        check_range("samples", self.samples, 36, 100_000)
        check_range("ground rail length", self.ground_mm, 700.0, 6000.0, "mm")

    @property
    def rails(self) -> tuple[float, ...]:
        """Rail lengths of the linkage type (crank, coupler/rod, rocker)."""
        return tuple(self.rails_mm[:3] if self.linkage_type == "four-bar" else self.rails_mm[:2])

    def settings(self) -> CheckSettings:
        # tuples keep the params hashable; the scene schema takes lists
        table = {"fidelity": self.fidelity, **{k: list(v) if isinstance(v, tuple) else v for k, v in self.check}}
        validate_check(table, "sweep")
        return check_settings(table, self.linkage_type, list(self.rails))

    def key(self) -> str:
        """Short hash of the parameters and of everything else a stored chunk depends on: the
        whole package (its code, part files and mass catalogue: a change to any of them must not
        resume from chunks computed before it)."""
        from rigfem.cache import package_hash

        src = dict(dataclasses.asdict(self), orig_dirs=ORIGINAL_DIRECTIONS, package=package_hash())
        return hashlib.sha256(json.dumps(src, sort_keys=True).encode()).hexdigest()[:12]


# ----------------------------------------------------------------------------- enumeration
def rig_rail_layout(length_mm: float) -> RailLayout:
    """The sweep rail's hole layout at ``length_mm`` (the rig's rail profile and plate)."""
    return rail_layout(RAIL, length_mm, PLATE)


def rail_lengths(length_mm: float, first: float = HOLE_PITCH_MM) -> list[float]:
    """Joint distances (mm) on the 60 mm grid from ``first`` whose coupling lands on holes."""
    lay = rig_rail_layout(length_mm)
    out, b = [], first
    while lay.fits(b):
        out.append(b)
        b += HOLE_PITCH_MM
    return out


def enumerate_configs(p: SweepParams) -> list[dict]:
    """Every configuration on the rig: each length on the hole grid within its rail (geometry/RIG.md §1-2);
    whether it assembles and meets the rig rules is decided later, per configuration.

    Four-bar: b2, b3, b4 on their rails, d on the ground rail from 660 mm (the rule; shorter
    ground lengths collide and are not enumerated).  Slider-crank: b2, b3 on their rails,
    slide line through O2 (offset 0: the ground rail carries both).
    """
    ground = [d for d in rail_lengths(p.ground_mm) if d >= MIN_GROUND_MM]
    if p.linkage_type == "four-bar":
        b2s, b3s, b4s = (rail_lengths(r) for r in p.rails)
        return [dict(b2=b2, b3=b3, b4=b4, d=d) for b2 in b2s for b3 in b3s for b4 in b4s for d in ground]
    b2s, b3s = (rail_lengths(r) for r in p.rails)
    return [dict(b2=b2, b3=b3, offset=0.0) for b2 in b2s for b3 in b3s if b2 + b3 <= max(ground)]


#: a renamed rule keeps its table column, so tables written before and after read alike
_COLUMN = {"on_the_hole_grid": "mountable"}


def _slug(name: str) -> str:
    slug = re.sub(r"[^a-z0-9]+", "_", name.split("(")[0].strip().lower()).strip("_")
    return _COLUMN.get(slug, slug)


def rules_row(p: SweepParams, cfg: dict) -> dict:
    """Every rig rule of a configuration: value and pass/fail columns, and whether all pass."""
    lengths = {k: cfg[k] for k in LENGTHS[p.linkage_type]}  # a cfg may also name its branch
    rules = fourbar_rules(**lengths) if p.linkage_type == "four-bar" else slider_crank_rules(**lengths)
    row = {}
    for r in rules:
        row[f"rule_{_slug(r.name)}"] = round(r.value, 6)
        row[f"rule_{_slug(r.name)}_ok"] = r.ok
    row["rules_ok"] = all(r.ok for r in rules)
    return row
