"""Scene files: the ``[linkage]`` table of a TOML file turned into a Linkage.

Only ``[linkage]`` is read; other tables (check settings added by other modules) are
ignored here.  Keys (lengths mm, angles deg)::

    [linkage]
    type = "four-bar"          # four-bar | slider-crank | inverted-slider-crank | quick-return
    b2 = 540.0                 # builder arguments (see rigfem.dynamics.mechanisms)
    speed_hz = 1.0             # or rpm = 20, or omega_rad_s = -3.12 (negative = clockwise)
    alpha_rad_s2 = 0.0         # crank angular acceleration at the instant (0 = constant speed)
    instant_deg = 60.0         # optional: the crank angle of the instant of interest
    textbook = true            # a textbook linkage, not a rig configuration: no rig rules
    masses = "rig"             # "rig" (the catalogue) or "none" (massless unless [linkage.bodies])
    [linkage.bodies.rod]       # optional per-body mass data (with masses = "none")
    mass_kg = 6.8
    com_local_mm = [175.0, 0.0]
    inertia_com_kg_mm2 = 92100.0
    [linkage.gas]              # optional compressor gas force on a slider-crank's slider
    p_N = 2000.0

Built-in scenes ship in ``rigfem/scenes`` and can be named without path or suffix.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from rigfem.dynamics.linkage import Linkage
from rigfem.dynamics.mechanisms import BUILDERS, compressor_gas_force
from rigfem.errors import InputError, check_range

_SPEED_KEYS = ("speed_hz", "rpm", "omega_rad_s")


_INFO_KEYS = ("type", "title", "notes", "masses", "bodies", "gas", "instant_deg", "alpha_rad_s2",
              "textbook") + _SPEED_KEYS


_BODY_KEYS = ("mass_kg", "com_local_mm", "inertia_com_kg_mm2", "point_masses")


@dataclass
class Scene:
    """A linkage read from a scene file, with its crank speed (Hz; negative = clockwise)."""

    name: str
    linkage: Linkage
    speed_hz: float
    table: dict = field(default_factory=dict)
    #: crank angular acceleration (rad/s²) and the crank angle of the instant of interest (deg)
    alpha_rad_s2: float = 0.0
    instant_deg: float | None = None
    #: a textbook linkage (MECHANISMS.md), not a rig configuration: the rig rules do not apply
    textbook: bool = False


def builtin_scenes() -> dict[str, Path]:
    """Built-in scene name -> path of the TOML file shipped with the package."""
    root = resources.files("rigfem") / "scenes"
    return {Path(p.name).stem: Path(str(p)) for p in root.iterdir() if p.name.endswith(".toml")}


def resolve(path_or_name: str | Path) -> Path:
    """A scene file path, or the built-in scene of that name; InputError if neither."""
    p = Path(path_or_name)
    if p.is_file():
        return p
    scenes = builtin_scenes()
    if str(path_or_name) in scenes:
        return scenes[str(path_or_name)]
    raise InputError(f"scene {str(path_or_name)!r} is neither a file nor a built-in scene "
                     f"({', '.join(sorted(scenes))})")


def _speed(t: dict) -> float:
    given = [k for k in _SPEED_KEYS if k in t]
    if len(given) > 1:
        raise InputError(f"[linkage] give only one of {', '.join(_SPEED_KEYS)}")
    if not given:
        return 1.0
    k = given[0]
    v = check_range(f"[linkage] {k}", t[k], -6000.0 if k == "rpm" else -100.0, 6000.0 if k == "rpm" else 100.0)
    if v == 0:
        raise InputError(f"[linkage] {k} must be non-zero")
    return {"speed_hz": v, "rpm": v / 60.0, "omega_rad_s": v / (2 * np.pi)}[k]


def linkage_from_table(t: dict) -> tuple[Linkage, float]:
    """Build (Linkage, speed_hz) from a ``[linkage]`` table (already parsed TOML)."""
    typ = t.get("type")
    if typ not in BUILDERS:
        raise InputError(f"[linkage] type = {typ!r} must be one of {', '.join(BUILDERS)}")
    builder = BUILDERS[typ]
    params = {k: v for k, v in t.items() if k not in _INFO_KEYS}
    masses = t.get("masses", "rig")
    if masses not in ("rig", "none"):
        raise InputError(f"[linkage] masses = {masses!r} must be 'rig' or 'none'")
    kwargs: dict = {"masses": None if masses == "none" else "rig"}
    bodies = t.get("bodies")
    if bodies:
        if masses != "none":
            raise InputError("[linkage.bodies] needs masses = 'none' (it replaces the rig catalogue)")
        for bname, bt in bodies.items():
            bad = set(bt) - set(_BODY_KEYS)
            if bad:
                raise InputError(f"[linkage.bodies.{bname}] unknown keys {sorted(bad)}; allowed {_BODY_KEYS}")
            if "mass_kg" in bt:
                check_range(f"[linkage.bodies.{bname}] mass_kg", bt["mass_kg"], 0.0, 1e4, "kg")
        kwargs["body_masses"] = bodies
    if "gas" in t:
        if typ != "slider-crank":
            raise InputError("[linkage.gas] applies to a slider-crank only")
        g = t["gas"]
        kwargs["slider_force"] = compressor_gas_force(float(t["b2"]), float(t["b3"]), **g)
    for k, v in params.items():
        if k in ("branch",):
            kwargs[k] = v
        elif k == "coupler_point":
            kwargs[k] = (check_range("[linkage] coupler_point.distance_mm", v["distance_mm"], 0, 1e4, "mm"),
                         check_range("[linkage] coupler_point.angle_deg", v["angle_deg"], -360, 360, "deg"))
        elif k in ("rails_mm",):
            kwargs[k] = tuple(float(x) for x in v)
        else:
            kwargs[k] = check_range(f"[linkage] {k}", v)
    try:
        lk = builder(**kwargs)
    except TypeError as exc:
        raise InputError(f"[linkage] bad keys for type {typ!r}: {exc}") from None
    return lk, _speed(t)


def load_scene(path_or_name: str | Path) -> Scene:
    """Read the ``[linkage]`` table of a scene file (or built-in scene name)."""
    p = resolve(path_or_name)
    try:
        data = tomllib.loads(p.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"scene {str(p)!r} is not valid TOML: {exc}") from None
    if "linkage" not in data:
        raise InputError(f"scene {str(p)!r} has no [linkage] table")
    t = data["linkage"]
    lk, speed = linkage_from_table(t)
    textbook = t.get("textbook", False)
    if not isinstance(textbook, bool):
        raise InputError(f"[linkage] textbook = {textbook!r} must be true or false")
    alpha = check_range("[linkage] alpha_rad_s2", t.get("alpha_rad_s2", 0.0), -1e7, 1e7, "rad/s²")
    instant = t.get("instant_deg")
    if instant is not None:
        instant = check_range("[linkage] instant_deg", instant, -360.0, 360.0, "deg")
    lk.meta["scene"] = p.stem
    lk.meta["textbook"] = textbook
    return Scene(p.stem, lk, speed, t, alpha, instant, textbook)
