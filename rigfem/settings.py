"""What a check does: the ``[check]`` table of a scene, with documented defaults.

Every field is optional::

    [check]
    modes = ["original", "cycle"]   # the 2013 study's load case, and the real crank cycle
    parts = ["crank_rail", "plate_A"]  # only these are meshed and solved (default: all of the linkage)
    fidelity = "standard"           # draft | standard | fine (see FIDELITY), or override below
    order = 2                       # element order (1 | 2)
    size_mm = 6.0                   # global mesh size
    local_size_mm = 1.2             # mesh size at the interfaces that carry load
    adaptive = true                 # refine each part coarse → preset only until decided (see LADDER;
                                    # fine: until its band is also within 5 % of its peak);
                                    # size_mm / local_size_mm mesh exactly that (no ladder)
    material = "rig_steel"          # rigfem.material library name, or a table {name, E, nu, sigma_u, density}
    load_factor = 1.4               # the study's factor on peak reactions (original mode)
    limit_factor = 0.5              # limit = limit_factor · σu (the study's σu/2)
    bearing_directions = 8          # directions of the unit bearing loads (cycle mode)
    [check.fatigue]                 # Goodman check beside the σu/2 verdict
    surface = "machined"; reliability = 0.9; size_mm = 19.0

The parts of each linkage type, and the joints that load them, are :data:`PARTS`.  Rail
lengths come from the linkage (``[linkage] rails_mm``), so dynamics and FE use the same rails;
the chosen parts are resolved against their definitions (rail layouts, kinds) once, here, and
handed down to the load cases.
"""

from __future__ import annotations

import difflib
import functools
import os
import warnings
from dataclasses import dataclass, field, fields, replace
from typing import TYPE_CHECKING

from rigfem.errors import InputError, check_range
from rigfem.material import Material, get_material, table_material

if TYPE_CHECKING:  # rig.layout loads numpy: imported where a scene is resolved, so the CLI starts light
    from rigfem.rig.layout import RigPart


#: environment variable that lifts rigfem's cost limits (set by ``rigfem --allow-large``)
ALLOW_LARGE_ENV = "RIGFEM_ALLOW_LARGE"


def allow_large() -> bool:
    """True when the user lifted the cost limits (memory and size estimates refuse nothing)."""
    return os.environ.get(ALLOW_LARGE_ENV, "") not in ("", "0")


#: the longest job (estimated wall time, hours) rigfem starts without ``rigfem --allow-large``
MAX_JOB_HOURS = 24.0

#: the scene every command that takes a configuration runs by default (check, reactions, kinematics, ...)
REFERENCE_SCENE = "final-cm"


@dataclass(frozen=True)
class MeshSettings:
    """How to mesh a part (mm): a global size, and a finer one near the surfaces that carry load.

    The one settings type from a preset to the mesher: a :class:`Preset` (and a check's
    :class:`CheckSettings`) *is* one, so ``mesh_part(part, preset("standard").refined(("hole",)))``
    meshes any part, built-in or custom, at a fidelity preset.
    """

    size_mm: float  #: global (largest) element size
    refine: tuple[str, ...] = ()  #: surface groups carrying load: refined, everything else coarse
    local_size_mm: float | None = None  #: size on the refined surfaces (default size_mm/4)
    refine_dist_mm: float | None = None  #: distance over which the size grows back (default 2*size_mm)
    min_quality: float = 0.1  #: smallest acceptable gmsh minSICN of a tetrahedron
    concentrate: tuple[str, ...] = ()  #: refined groups that raise stress (fillets): half the local size

    def __post_init__(self) -> None:
        """The invariants every mesher relies on: sizes finite and > 0 (at most 10 m), a quality in [0, 1]."""
        for name, v in (("size_mm", self.size_mm), ("local_size_mm", self.local_size_mm),
                        ("refine_dist_mm", self.refine_dist_mm)):
            if v is not None:
                check_range(name, v, 0.0, 1e4, "mm", lo_open=True)
        check_range("min_quality", self.min_quality, 0.0, 1.0)

    @property
    def near_mm(self) -> float:
        """The size on the refined surfaces: ``local_size_mm``, or size_mm/4 when not given."""
        return self.local_size_mm if self.local_size_mm is not None else self.size_mm / 4

    @property
    def dist_mm(self) -> float:
        """The grading distance: ``refine_dist_mm``, or 2*size_mm when not given."""
        return self.refine_dist_mm if self.refine_dist_mm is not None else 2 * self.size_mm

    def refined(self, refine: tuple[str, ...], concentrate: tuple[str, ...] = ()):
        """The same settings, refined on the surface groups ``refine`` (``concentrate`` among them)."""
        return replace(self, refine=tuple(refine), concentrate=tuple(concentrate))

    def key(self) -> dict:
        """The mesh fields only (what the mesh depends on), resolved: the mesh cache's key."""
        return {"size_mm": self.size_mm, "refine": sorted(self.refine), "local_size_mm": self.near_mm,
                "refine_dist_mm": self.dist_mm, "min_quality": self.min_quality,
                "concentrate": sorted(self.concentrate)}


def check_groups(part: str, settings: MeshSettings, groups) -> None:
    """The surface groups ``settings`` refines are groups of the part (``groups``: its names, known
    once gmsh has built it); InputError listing them otherwise."""
    unknown = [g for g in settings.refine + settings.concentrate if g not in groups]
    if unknown:
        raise InputError(f"refine: {', '.join(unknown)} not a surface group of {part}; "
                         f"groups: {', '.join(sorted(groups))}")


#: MeshSettings' keywords before 0.1 (README's "Your own part"), still taken until rigfem 0.3
_OLD_MESH_KEYWORDS = {"size": "size_mm", "refine_size": "local_size_mm", "refine_dist": "refine_dist_mm"}


def _old_keywords(init):
    """MeshSettings' constructor taking its pre-0.1 keywords (``size``, ``refine_size``,
    ``refine_dist``) with a DeprecationWarning, so scripts written against them still run."""

    @functools.wraps(init)
    def __init__(self, *args, **kwargs):
        for old, new in _OLD_MESH_KEYWORDS.items():
            if old in kwargs:
                warnings.warn(f"MeshSettings({old}=...) is deprecated, use {new}=...; the old name goes in "
                              f"rigfem 0.3", DeprecationWarning, stacklevel=2)
                kwargs[new] = kwargs.pop(old)
        init(self, *args, **kwargs)

    return __init__


MeshSettings.__init__ = _old_keywords(MeshSettings.__init__)  # type: ignore[method-assign]


@dataclass(frozen=True)
class Preset(MeshSettings):
    """A fidelity preset: mesh settings plus the FE fields, element order and bearing directions."""

    order: int = 2  #: element order (1 | 2)
    bearing_directions: int = 8  #: directions of the unit bearing loads (cycle mode)

    def __getitem__(self, key: str):
        """``FIDELITY["standard"]["order"]``: the mapping access of the presets before 0.1
        (deprecated, goes in rigfem 0.3; read the attribute)."""
        if key not in {f.name for f in fields(Preset)}:
            raise KeyError(key)
        warnings.warn(f"preset[{key!r}] is deprecated, use preset.{key}; the mapping access goes in rigfem 0.3",
                      DeprecationWarning, stacklevel=2)
        return getattr(self, key)


#: fidelity presets: element order, global and local mesh size (mm), bearing directions
#: (8 directions are within 0.7 % of 48 on the reference parts: results/convergence/sampling.md;
#: errors against the extrapolated peaks per part: results/convergence/summary.md — plate and
#: post within 5 / 1.7 / 0.9 %, rails up to 13 / 8 / 5 % low where a groove or hole facets)
FIDELITY: dict[str, Preset] = {
    "draft": Preset(size_mm=8.0, local_size_mm=1.7, order=2, bearing_directions=8),
    "standard": Preset(size_mm=6.0, local_size_mm=1.2, order=2, bearing_directions=8),
    "fine": Preset(size_mm=4.0, local_size_mm=0.6, order=2, bearing_directions=12),
}


def preset(name: str) -> Preset:
    """The fidelity preset ``name`` (draft | standard | fine)."""
    if name not in FIDELITY:
        raise InputError(f"fidelity = {str(name)[:40]!r} must be one of {', '.join(FIDELITY)}")
    return FIDELITY[name]

#: reporting target of each preset, % of the allowable: a check refines a part (:data:`LADDER`)
#: until its band's half-width ``peak·error_pct/100`` is within this share of the allowable and the
#: band does not straddle it.  Each preset meets it against the extrapolated peak of the reference
#: parts (results/convergence/summary.md); the sweep, which estimates no band, reports it as its band.
PRESET_ERROR_PCT: dict[str, float] = {"draft": 10.0, "standard": 3.0, "fine": 1.0}

#: the second target of a preset, % of the peak: ``fine`` refines every part, however far below the
#: limit, until its band is within ±5 % of its own peak (or it reaches the fine mesh), so "fine"
#: means a fine answer for every part, not only a decided verdict; draft and standard have none
#: (a part far below the limit stops as soon as its verdict is decided within PRESET_ERROR_PCT)
PRESET_PEAK_PCT: dict[str, float | None] = {"draft": None, "standard": None, "fine": 5.0}

#: the adaptive ladder's first level, coarser than draft (global, local size mm): parts far below
#: the limit are decided on it (results/benchmarks/adaptive.md)
COARSE = Preset(size_mm=12.0, local_size_mm=2.4)

#: the levels a check climbs, coarsest first; a check at preset ``p`` stops at ``p`` at the latest
LADDER: dict[str, Preset] = {"coarse": COARSE, **FIDELITY}


def ladder(fidelity: str) -> list[tuple[str, Preset]]:
    """The adaptive levels (name, preset) of a check at ``fidelity``: coarse up to that preset."""
    names = list(LADDER)
    return [(n, LADDER[n]) for n in names[:names.index(fidelity) + 1]]


MODES = ("original", "cycle")

#: the dynamics' mass models, ``[check].mass_model`` (rigfem.dynamics.cycle.simulate)
MODELS = ("rigid-body", "original")


def check_mass_model(model: str, linkage_meta: dict) -> None:
    """InputError when the mass model ``original`` (the 2013 program) is asked of a linkage other
    than the four-bar with the rig masses (``linkage_meta``: a Linkage's ``meta``).  Called where
    the model and the linkage meet: the scene (rigfem.job), rigfem reactions, and
    :func:`rigfem.dynamics.cycle.simulate` (a script's call)."""
    if model == "original" and (linkage_meta.get("type") != "four-bar" or linkage_meta.get("masses") != "rig"):
        raise InputError(f"model 'original' exists only for the four-bar with the rig masses, "
                         f"not {linkage_meta.get('type')!r} with masses {linkage_meta.get('masses')!r}")


RAIL = "rail_size25"


PLATE = "PF_4b_006"


POST = "PF_4b_003_v2"


#: parts of each linkage type: rails (pivot joint, far joint, default length mm) and fittings
#: (part, joint, rail it is screwed to).  geometry/RIG.md §3-4.
PARTS: dict[str, dict[str, dict]] = {
    "four-bar": {
        "crank_rail": {"part": RAIL, "pivot": "O2", "far": "A", "length": 700.0, "driven": True},
        "coupler_rail": {"part": RAIL, "pivot": "A", "far": "B", "length": 1000.0},
        "rocker_rail": {"part": RAIL, "pivot": "O4", "far": "B", "length": 1000.0},
        "plate_A": {"part": PLATE, "joint": "A", "on": "crank_rail"},
        "plate_B": {"part": PLATE, "joint": "B", "on": "coupler_rail"},
        "post_B": {"part": POST, "joint": "B", "on": "rocker_rail"},
    },
    "slider-crank": {
        "crank_rail": {"part": RAIL, "pivot": "O2", "far": "A", "length": 700.0, "driven": True},
        "rod_rail": {"part": RAIL, "pivot": "A", "far": "B", "length": 1000.0},
        "plate_A": {"part": PLATE, "joint": "A", "on": "crank_rail"},
        "plate_B": {"part": PLATE, "joint": "B", "on": "rod_rail"},
    },
}


@dataclass(frozen=True, kw_only=True)
class CheckSettings(Preset):
    """Validated ``[check]`` settings of a scene: its preset (possibly overridden) and the check's own fields."""

    linkage_type: str
    parts: dict[str, dict]  #: instance name -> spec (see PARTS), only those to check
    rig: dict[str, RigPart]  #: the same parts resolved against their definitions (geometry/), once
    modes: tuple[str, ...] = MODES
    fidelity: str = "standard"
    material: Material = field(default_factory=lambda: get_material("rig_steel"))
    load_factor: float = 1.4
    limit_factor: float = 0.5
    fatigue: dict = field(default_factory=lambda: {"surface": "machined", "reliability": 0.9,
                                                   "size_mm": 19.0})
    adaptive: bool = True  #: climb :func:`ladder` per part until decided (off when sizes are forced)

    @property
    def target_pct(self) -> float:
        """The reporting target: the band's half-width, % of the allowable (:data:`PRESET_ERROR_PCT`)."""
        return PRESET_ERROR_PCT[self.fidelity]

    @property
    def target_peak_pct(self) -> float | None:
        """The second reporting target, the band's half-width in % of the peak (:data:`PRESET_PEAK_PCT`;
        None: none)."""
        return PRESET_PEAK_PCT[self.fidelity]

    def asked(self) -> dict:
        """What the check asked of each part's mesh (report.json's ``mesh.asked``): the preset, its
        targets (% of the allowable, % of the peak or None) and the finest level it may reach."""
        levels = self.levels()
        return {"fidelity": self.fidelity, "adaptive": self.adaptive, "target_pct_of_allowable": self.target_pct,
                "target_pct_of_peak": self.target_peak_pct, "cap": levels[-1][0]}

    def levels(self) -> list[tuple[str, "CheckSettings"]]:
        """The mesh levels to try, coarsest first: the ladder, or only these settings when not adaptive."""
        if not self.adaptive:
            fixed = FIDELITY[self.fidelity]
            same = (self.size_mm, self.near_mm) == (fixed.size_mm, fixed.near_mm)
            return [(self.fidelity if same else "forced", self)]
        return [(n, replace(self, size_mm=p.size_mm, local_size_mm=p.local_size_mm)) for n, p in ladder(self.fidelity)]


def check_settings(table: dict, linkage_type: str, rails_mm: list[float] | None = None) -> CheckSettings:
    """The settings of a ``[check]`` table (:func:`part_settings`) with the material it names
    (:func:`rigfem.material.table_material`)."""
    return replace(part_settings(table, linkage_type, rails_mm),
                   material=table_material(table.get("material", "rig_steel")))


def part_settings(table: dict, linkage_type: str, rails_mm: list[float] | None = None) -> CheckSettings:
    """Build the settings of a ``[check]`` table (may be empty) for a linkage of ``linkage_type``,
    all but its material (the default until :func:`check_settings` or the check's scene
    loading resolves the table's: after the rig rules, which need no material).

    ``table`` has been validated by ``rigfem.schema.CheckTable`` (keys, types, ranges); here
    only what depends on the linkage is checked: the parts it has.  ``rails_mm``: the
    linkage's rail lengths in the order of its rails in :data:`PARTS`.
    """
    from rigfem.rig.layout import resolve_parts

    if linkage_type not in PARTS:
        raise InputError(f"linkage type {linkage_type!r} has no stress check yet; checkable types: "
                         f"{', '.join(PARTS)}")
    catalogue = {k: dict(v) for k, v in PARTS[linkage_type].items()}
    for name, length in zip([k for k, v in catalogue.items() if "length" in v], rails_mm or []):
        catalogue[name]["length"] = float(length)
    chosen = table.get("parts") or list(catalogue)
    for p in chosen:
        if p not in catalogue:
            near = ([k for k in catalogue if k.lower() == str(p).lower()]
                    or difflib.get_close_matches(str(p), list(catalogue), n=1))
            hint = f"; did you mean {near[0]!r}?" if near else ""
            raise InputError(f"[check].parts: {str(p)[:40]!r} is not a part of a {linkage_type}{hint} "
                             f"(parts: {', '.join(catalogue)})")
    parts = {}
    for p in chosen:
        parts[p] = catalogue[p]
        on = catalogue[p].get("on")
        if on:  # a fitting needs its rail's placement (not a check of the rail)
            parts[p] = dict(catalogue[p], rail=catalogue[on])
    fid = table.get("fidelity", "standard")
    chosen_preset = replace(preset(fid), **{k: table[k] for k in ("order", "size_mm", "local_size_mm",
                                                                  "bearing_directions") if k in table})
    size, local = float(chosen_preset.size_mm), float(chosen_preset.near_mm)
    if local > size:
        raise InputError(f"[check].local_size_mm = {local:g} mm must not exceed size_mm = {size:g} mm")
    fatigue = {"surface": "machined", "reliability": 0.9, "size_mm": 19.0, **table.get("fatigue", {})}
    mesh = {f.name: getattr(chosen_preset, f.name) for f in fields(Preset)}
    mesh.update(size_mm=size, local_size_mm=local, order=int(chosen_preset.order),
                bearing_directions=int(chosen_preset.bearing_directions))
    return CheckSettings(
        **mesh, linkage_type=linkage_type, parts=parts, rig=resolve_parts(parts, PLATE), modes=tuple(table.get("modes", MODES)), fidelity=fid,
        load_factor=float(table.get("load_factor", 1.4)),
        limit_factor=float(table.get("limit_factor", 0.5)), fatigue=fatigue,
        adaptive=bool(table.get("adaptive", True)) and not ({"size_mm", "local_size_mm"} & set(table)))
