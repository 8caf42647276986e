"""Scene files: a TOML file read as validated, plain data.

The whole file is checked against :mod:`rigfem.schema` first (unknown tables and keys,
types, ranges).  Content that passed the same schema before is not checked again: a verified
cache entry (:mod:`rigfem.cache`) keyed by the file's SHA-256 and pydantic's version (and, as
every entry, by the package's code) records the pass, so reading a known scene loads no pydantic (issue 26:
``rigfem kinematics SCENE`` is a light command).  The ``[linkage]`` table becomes a
:class:`Scene`: the linkage's type and builder arguments, its speed and what it names
(masses, a gas force).  Nothing is computed here: :func:`rigfem.linkage.mechanisms.build`
makes the linkage, the dynamics resolve the forces
(:func:`rigfem.dynamics.forces.loaded_linkage`).  Keys (lengths mm, angles deg)::

    [linkage]
    type = "four-bar"          # four-bar | slider-crank | inverted-slider-crank | quick-return
    b2 = 540.0                 # builder arguments (see rigfem.linkage.mechanisms)
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

import hashlib
import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from importlib.metadata import version
from pathlib import Path

from rigfem.errors import InputError, decode_text, plain, read_at_most
from rigfem.cache import Cache, resolve as resolve_cache

#: deepest nesting of tables/arrays a scene may have (the schema itself needs 4)
MAX_DEPTH = 8
#: largest scene file read (bytes)
MAX_BYTES = 1_000_000

_SPEED_KEYS = ("speed_hz", "rpm", "omega_rad_s")


_INFO_KEYS = ("type", "title", "notes", "masses", "bodies", "gas", "instant_deg", "alpha_rad_s2",
              "textbook") + _SPEED_KEYS


@dataclass
class Scene:
    """A scene file's linkage as plain data: its type and builder arguments (lengths mm, angles
    deg), its crank speed (Hz; negative = clockwise) and the gas force it names (or None)."""

    name: str
    linkage_type: str
    params: dict
    speed_hz: float
    table: dict = field(default_factory=dict)
    #: crank angular acceleration (rad/s²) and the crank angle of the instant of interest (deg)
    alpha_rad_s2: float = 0.0
    instant_deg: float | None = None
    #: a textbook linkage (geometry/MECHANISMS.md), not a rig configuration: the rig rules do not apply
    textbook: bool = False
    raw: dict = field(default_factory=dict)  #: the whole scene file (raw TOML, validated)
    #: ``[linkage.gas]``: the compressor's gas force on the slider (p_N, L_mm, c_mm), or None
    gas: dict | None = None


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
    return {"speed_hz": v, "rpm": v / 60.0, "omega_rad_s": v / (2 * math.pi)}[k]


def linkage_params(t: dict) -> dict:
    """The builder arguments (:data:`rigfem.linkage.mechanisms.BUILDERS`) of a ``[linkage]``
    table (raw TOML, validated by rigfem.schema): lengths as floats, pairs as tuples."""
    masses = t.get("masses", "rig")
    kwargs: dict = {"masses": None if masses == "none" else "rig"}
    if t.get("bodies"):
        kwargs["body_masses"] = t["bodies"]
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
    return kwargs


def _depth(obj, level: int = 0) -> int:
    if level > MAX_DEPTH:
        return level
    if isinstance(obj, dict):
        return max([_depth(v, level + 1) for v in obj.values()] or [level])
    if isinstance(obj, list):
        return max([_depth(v, level + 1) for v in obj] or [level])
    return level


def read_toml(path: Path) -> tuple[dict, str]:
    """Raw TOML of a scene file and the SHA-256 of the bytes it was read from; InputError (one
    line) if unreadable, binary, not UTF-8, not TOML or nested deeper than :data:`MAX_DEPTH`."""
    name = plain(str(path), 120)
    blob = read_at_most(path, MAX_BYTES, f"scene {name!r}", "a scene file")
    text = decode_text(blob, f"scene {name!r}")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"scene {name!r} is not valid TOML: {plain(exc, 160)}") from None
    except RecursionError:
        raise InputError(f"scene {name!r} is nested too deeply (at most {MAX_DEPTH} levels)") from None
    if _depth(data) > MAX_DEPTH:
        raise InputError(f"scene {name!r} is nested too deeply (at most {MAX_DEPTH} levels)")
    return data, hashlib.sha256(blob).hexdigest()


def _validate(data: dict, digest: str, name: str, cache: Cache) -> None:
    """Check a scene's raw TOML (``digest``: SHA-256 of its bytes) against :mod:`rigfem.schema`,
    unless this content passed the same schema (package and pydantic version) before."""
    inputs = {"scene": digest, "pydantic": version("pydantic")}
    if cache.get("scenes", inputs, lambda entry: True):
        return
    from rigfem.schema import validate_scene  # pydantic: loaded for content not validated before

    validate_scene(data, name)
    cache.put("scenes", inputs, lambda tmp: None)  # only valid content is recorded


def load_scene(path_or_name: str | Path, cache: Cache | None = None) -> Scene:
    """Read a scene file (or built-in scene name) as plain, validated data (``cache``: where a
    validation is remembered; None: the environment's, :func:`rigfem.cache.resolve`)."""
    p = resolve(path_or_name)
    data, digest = read_toml(p)
    _validate(data, digest, p.name, resolve_cache(cache))
    t = data["linkage"]
    return Scene(p.stem, t["type"], linkage_params(t), _speed(t), t, float(t.get("alpha_rad_s2", 0.0)),
                 t.get("instant_deg"), bool(t.get("textbook", False)), data,
                 dict(t["gas"]) if "gas" in t else None)
