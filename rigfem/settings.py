"""What a check does: the ``[check]`` table of a scene, with documented defaults.

Every field is optional::

    [check]
    modes = ["original", "cycle"]   # the 2013 study's load case, and the real crank cycle
    parts = ["crank_rail", "plate_A"]  # only these are meshed and solved (default: all of the linkage)
    fidelity = "standard"           # draft | standard | fine (see FIDELITY), or override below
    order = 2                       # element order (1 | 2)
    size_mm = 6.0                   # global mesh size
    local_size_mm = 1.2             # mesh size at the interfaces that carry load
    material = "rig_steel"          # rigfem.material library name, or a table {name, E, nu, sigma_u, density}
    load_factor = 1.4               # the study's factor on peak reactions (original mode)
    limit_factor = 0.5              # limit = limit_factor · σu (the study's σu/2)
    bearing_directions = 8          # directions of the unit bearing loads (cycle mode)
    [check.fatigue]                 # Goodman check beside the σu/2 verdict
    surface = "machined"; reliability = 0.9; size_mm = 19.0

The parts of each linkage type, and the joints that load them, are :data:`PARTS`.  Rail
lengths come from the linkage (``[linkage] rails_mm``), so dynamics and FE use the same rails.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rigfem.errors import InputError, check_range
from rigfem.material import Material, get_material, material_from_dict

#: fidelity presets: element order, global and local mesh size (mm), bearing directions
#: (8 directions are within 0.7 % of 48 on the reference parts: results/convergence/sampling.md;
#: errors against the extrapolated peaks per part: results/convergence/summary.md — plate and
#: post within 5 / 1.7 / 0.9 %, rails up to 13 / 8 / 5 % low where a groove or hole facets)
FIDELITY: dict[str, dict] = {
    "draft": {"order": 2, "size_mm": 8.0, "local_size_mm": 1.7, "bearing_directions": 8},
    "standard": {"order": 2, "size_mm": 6.0, "local_size_mm": 1.2, "bearing_directions": 8},
    "fine": {"order": 2, "size_mm": 4.0, "local_size_mm": 0.6, "bearing_directions": 12},
}
#: accuracy target of each preset against the extrapolated peak, % (met by every converging
#: peak: results/convergence/summary.md); the sweep uses it as its error band
PRESET_ERROR_PCT: dict[str, float] = {"draft": 10.0, "standard": 3.0, "fine": 1.0}


MODES = ("original", "cycle")


RAIL = "rail_size25"


PLATE = "PF_4b_006"


POST = "PF_4b_003_v2"


#: parts of each linkage type: rails (pivot joint, far joint, default length mm) and fittings
#: (part, joint, rail it is screwed to).  RIG.md §3-4.
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


@dataclass(frozen=True)
class CheckSettings:
    """Validated ``[check]`` settings of a scene."""

    linkage_type: str
    parts: dict[str, dict]  #: instance name -> spec (see PARTS), only those to check
    modes: tuple[str, ...] = MODES
    fidelity: str = "standard"
    order: int = FIDELITY["standard"]["order"]
    size_mm: float = FIDELITY["standard"]["size_mm"]
    local_size_mm: float = FIDELITY["standard"]["local_size_mm"]
    bearing_directions: int = FIDELITY["standard"]["bearing_directions"]
    material: Material = field(default_factory=lambda: get_material("rig_steel"))
    load_factor: float = 1.4
    limit_factor: float = 0.5
    fatigue: dict = field(default_factory=lambda: {"surface": "machined", "reliability": 0.9,
                                                   "size_mm": 19.0})


_KEYS = {"modes", "parts", "fidelity", "order", "size_mm", "local_size_mm", "material", "load_factor",
         "limit_factor", "bearing_directions", "fatigue"}


def check_settings(table: dict, linkage_type: str, rails_mm: list[float] | None = None) -> CheckSettings:
    """Validate a scene's ``[check]`` table (may be empty) for a linkage of ``linkage_type``.

    ``rails_mm``: the linkage's rail lengths in the order of its rails in :data:`PARTS`.
    """
    unknown = sorted(set(table) - _KEYS)
    if unknown:
        raise InputError(f"[check] has unknown field(s) {', '.join(unknown)}; allowed: {', '.join(sorted(_KEYS))}")
    if linkage_type not in PARTS:
        raise InputError(f"linkage type {linkage_type!r} has no stress check yet; checkable types: "
                         f"{', '.join(PARTS)}")
    catalogue = {k: dict(v) for k, v in PARTS[linkage_type].items()}
    for name, length in zip([k for k, v in catalogue.items() if "length" in v], rails_mm or []):
        catalogue[name]["length"] = check_range(f"[linkage] rails_mm ({name})", length, 100.0, 3000.0, "mm")
    chosen = table.get("parts", list(catalogue))
    bad = [p for p in chosen if p not in catalogue]
    if bad or not chosen:
        raise InputError(f"[check] parts {bad or '[]'} not allowed; parts of a {linkage_type}: "
                         f"{', '.join(catalogue)}")
    parts = {}
    for p in chosen:
        parts[p] = catalogue[p]
        on = catalogue[p].get("on")
        if on:  # a fitting needs its rail's placement (not a check of the rail)
            parts[p] = dict(catalogue[p], rail=catalogue[on])
    modes = tuple(table.get("modes", MODES))
    if not modes or any(m not in MODES for m in modes):
        raise InputError(f"[check] modes = {list(modes)} must be a non-empty subset of {list(MODES)}")
    fid = table.get("fidelity", "standard")
    if fid not in FIDELITY:
        raise InputError(f"[check] fidelity = {fid!r} must be one of {', '.join(FIDELITY)}")
    preset = dict(FIDELITY[fid])
    order = table.get("order", preset["order"])
    if order not in (1, 2):
        raise InputError(f"[check] order = {order!r} must be 1 or 2")
    size = check_range("[check] size_mm", table.get("size_mm", preset["size_mm"]), 0.1, 100.0, "mm")
    local = check_range("[check] local_size_mm", table.get("local_size_mm", preset["local_size_mm"]),
                        0.05, size, "mm")
    ndir = table.get("bearing_directions", preset["bearing_directions"])
    if not isinstance(ndir, int) or not 4 <= ndir <= 72:
        raise InputError(f"[check] bearing_directions = {ndir!r} must be a whole number in [4, 72]")
    mat = table.get("material", "rig_steel")
    material = material_from_dict(mat) if isinstance(mat, dict) else get_material(str(mat))
    fatigue = {"surface": "machined", "reliability": 0.9, "size_mm": 19.0, **table.get("fatigue", {})}
    return CheckSettings(
        linkage_type, parts, modes, fid, int(order), size, local, ndir, material,
        check_range("[check] load_factor", table.get("load_factor", 1.4), 0.0, 100.0, lo_open=True),
        check_range("[check] limit_factor", table.get("limit_factor", 0.5), 0.0, 1.0, lo_open=True),
        fatigue)
