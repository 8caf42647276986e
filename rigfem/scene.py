"""Scene files: the ``[linkage]`` table of a TOML file turned into a Linkage.

The whole file is checked against :mod:`rigfem.schema` first (unknown tables and keys,
types, ranges); only ``[linkage]`` is built here.  Keys (lengths mm, angles deg)::

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

from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np
from pydantic import ValidationError

from rigfem.dynamics.linkage import Linkage
from rigfem.dynamics.mechanisms import BUILDERS, compressor_gas_force
from rigfem.errors import InputError, plain
from rigfem.schema import SceneFile, input_error, load_validated

_SPEED_KEYS = ("speed_hz", "rpm", "omega_rad_s")


_INFO_KEYS = ("type", "title", "notes", "masses", "bodies", "gas", "instant_deg", "alpha_rad_s2",
              "textbook") + _SPEED_KEYS


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
    #: a textbook linkage (geometry/MECHANISMS.md), not a rig configuration: the rig rules do not apply
    textbook: bool = False
    raw: dict = field(default_factory=dict)  #: the whole scene file (raw TOML, validated)


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
    raise InputError(f"scene {plain(str(path_or_name), 120)!r} is neither a file nor a built-in scene "
                     f"({', '.join(sorted(scenes))})")


def _speed(t: dict) -> float:
    """Crank speed (Hz) of a validated ``[linkage]`` table (default 1 Hz)."""
    k = next((k for k in _SPEED_KEYS if t.get(k) is not None), None)
    if k is None:
        return 1.0
    v = float(t[k])
    return {"speed_hz": v, "rpm": v / 60.0, "omega_rad_s": v / (2 * np.pi)}[k]


def linkage_from_table(t: dict) -> tuple[Linkage, float]:
    """Build (Linkage, speed_hz) from a ``[linkage]`` table (raw TOML, validated by rigfem.schema)."""
    try:
        SceneFile.model_validate({"linkage": t})
    except ValidationError as exc:
        raise input_error(exc, {"linkage": t}) from None
    typ = t["type"]
    masses = t.get("masses", "rig")
    kwargs: dict = {"masses": None if masses == "none" else "rig"}
    if t.get("bodies"):
        kwargs["body_masses"] = t["bodies"]
    if "gas" in t:
        kwargs["slider_force"] = compressor_gas_force(float(t["b2"]), float(t["b3"]), **t["gas"])
    for k, v in t.items():
        if k in _INFO_KEYS:
            continue
        if k == "coupler_point":
            kwargs[k] = (float(v["distance_mm"]), float(v["angle_deg"]))
        elif k == "rails_mm":
            kwargs[k] = tuple(float(x) for x in v)
        elif k == "branch":
            kwargs[k] = v
        else:
            kwargs[k] = float(v)
    return BUILDERS[typ](**kwargs), _speed(t)


def load_scene(path_or_name: str | Path) -> Scene:
    """Read the ``[linkage]`` table of a scene file (or built-in scene name)."""
    p = resolve(path_or_name)
    data, _ = load_validated(p)
    t = data["linkage"]
    lk, speed = linkage_from_table(t)
    textbook = bool(t.get("textbook", False))
    lk.meta["scene"] = p.stem
    lk.meta["textbook"] = textbook
    return Scene(p.stem, lk, speed, t, float(t.get("alpha_rad_s2", 0.0)), t.get("instant_deg"), textbook, data)
