"""Part definitions (geometry/*.toml) and their OpenCASCADE geometry in gmsh.

Units: mm (dimensions), kg/m^3 (density in the files), kg (masses returned here).

A part file lists every dimension with value, unit and source ("catalogue", "2013 study"
or "assumed: ...") so an engineer corrects a dimension without touching code.  Known parts:

- ``rail_size25`` (kind ``rail``): x along the rail from x=0 to x=L, y across the width
  (y=0 mid-width), z up (z=0 bottom mounting face, z=H top).  Vertical mounting holes at
  x = first_offset + i*pitch (as many as fit with the same end distance on the far end).
  Surface groups: ``hole_00``, ``hole_01``, ... (through-bore walls, in x order), ``cbore_00``...
  (counterbore walls), ``cbore_floor_00``... (annulus where the screw head bears), ``ends``,
  ``bottom``, ``top``, ``sides`` (and ``grooves`` if modelled; a waist's faces are ``sides``);
  volume group ``rail``.
- ``PF_4b_006``, ``PF_4b_005_v2``, ``PF_4b_004_v2``, ``PF_4b_002_v2``, ``PF_4b_001_v2`` (kind
  ``plate``, thickness variants of one definition): z along the bore axis, z=0 the face against
  the rail, origin on the axis, screws on the x axis.  Groups ``bore`` (bearing seat),
  ``screw_1`` (x<0), ``screw_2`` (x>0), ``bottom``, ``top`` (all faces normal to +z), ``rim``;
  volume ``plate``.
- ``PF_4b_003_v2`` (kind ``iprofile``): x along the profile, y across the flanges, z up.
  Groups ``screw_1``..``screw_4`` (bottom flange y<0, y>0, top flange y<0, y>0), ``base``
  (z=0), ``top`` (z=height), ``fillets`` (if ``fillet_radius`` > 0: the four web-flange root
  fillets; 0 keeps sharp corners, a stress singularity); volume ``iprofile``.
- Custom parts: a path to a ``.geo`` file (its physical groups are used; it may ``Merge`` a
  STEP/BREP) or a ``.step``/``.stp``/``.brep`` file whose named entities become groups.

:func:`build` must run inside :func:`gmsh_session`; it returns the analytic :class:`Hole`
of every cylindrical group so loads and supports attach by name.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from rigfem.errors import InputError, check_range

if TYPE_CHECKING:  # numpy only where hole positions are made: `rigfem parts` lists without it
    import numpy as np

#: folder with the part definition files: the top-level geometry/, installed as rigfem.geometry
GEOMETRY_DIR = Path(str(resources.files("rigfem.geometry")))


#: allowed prefixes of a dimension's source
SOURCES = ("catalogue", "2013 study", "assumed")


#: smallest wall left between a hole and an edge or another hole, mm
MIN_WALL = 1.0


_CUSTOM_SUFFIXES = (".geo", ".step", ".stp", ".brep")


@dataclass(frozen=True)
class Dimension:
    """One documented dimension of a part file."""

    value: float
    unit: str
    source: str


@dataclass(frozen=True)
class PartDef:
    """A validated part definition: kind, dimensions (mm) and density (kg/m^3)."""

    name: str
    kind: str  #: "rail", "plate", "iprofile" or "custom"
    dims: dict[str, Dimension] = field(default_factory=dict)
    density: float = 7850.0  #: kg/m^3
    description: str = ""
    path: Path | None = None  #: definition file (TOML, or the custom geometry file)
    reference: dict[str, Dimension] = field(default_factory=dict)  #: figures to compare with

    def __getitem__(self, key: str) -> float:
        return self.dims[key].value

    def content_hash(self) -> str:
        """SHA-256 of everything that shapes the geometry (for the mesh cache)."""
        payload = {"name": self.name, "kind": self.kind, "density": self.density,
                   "dims": {k: d.value for k, d in sorted(self.dims.items())}}
        h = hashlib.sha256(json.dumps(payload, sort_keys=True).encode())
        if self.kind == "custom" and self.path is not None:
            h.update(self.path.read_bytes())
        return h.hexdigest()


def _read_dims(table: dict, where: str) -> dict[str, Dimension]:
    dims = {}
    for key, entry in table.items():
        if not isinstance(entry, dict) or not {"value", "unit", "source"} <= entry.keys():
            raise InputError(f"{where}.{key} needs value, unit and source")
        if not str(entry["source"]).startswith(SOURCES):
            raise InputError(f"{where}.{key}.source must start with one of {', '.join(SOURCES)}")
        dims[key] = Dimension(check_range(f"{where}.{key}", entry["value"]), str(entry["unit"]),
                              str(entry["source"]))
    return dims


def _read_toml(path: Path) -> dict:
    try:
        with path.open("rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"part file {path}: {exc}") from None


def known_parts(geometry_dir: Path = GEOMETRY_DIR) -> dict[str, tuple[Path, str | None]]:
    """Name -> (definition file, variant or None) for every part under ``geometry_dir``."""
    parts: dict[str, tuple[Path, str | None]] = {}
    for path in sorted(geometry_dir.glob("*.toml")):
        data = _read_toml(path)
        variants = data.get("variants", {})
        if variants:
            for v in variants:
                parts[v] = (path, v)
        else:
            parts[data["part"]["name"]] = (path, None)
    return parts


def load_part(name: str, overrides: dict[str, float] | None = None,
              geometry_dir: Path = GEOMETRY_DIR) -> PartDef:
    """Load a known part by name (or a custom geometry file by path) and validate it.

    ``overrides`` replaces dimension values, e.g. ``{"length": 700}`` for a 700 mm rail.
    Definitions are read once per process (a sweep asks for the same parts thousands of times).
    """
    return _load_part(name, tuple(sorted((overrides or {}).items())), Path(geometry_dir))


@functools.lru_cache(maxsize=512)
def _load_part(name: str, override_items: tuple, geometry_dir: Path) -> PartDef:
    overrides = dict(override_items)
    if Path(name).suffix.lower() in _CUSTOM_SUFFIXES:
        path = Path(name)
        if not path.is_file():
            raise InputError(f"part file {name} does not exist")
        if overrides:
            raise InputError(f"dimension overrides ({', '.join(overrides)}) do not apply to a custom part")
        return PartDef(name=path.stem, kind="custom", path=path.resolve(),
                       description=f"custom part from {path.name}")
    parts = known_parts(geometry_dir)
    if name not in parts:
        raise InputError(f"part {name!r} is unknown; known parts: {', '.join(parts)} "
                         f"(or a .geo/.step/.stp/.brep file)")
    path, variant = parts[name]
    data = _read_toml(path)
    dims = _read_dims(data.get("dimensions", {}), "dimensions")
    reference = _read_dims(data.get("reference", {}), "reference")
    if variant is not None:
        vt = dict(data["variants"][variant])
        reference.update(_read_dims(vt.pop("reference", {}), f"variants.{variant}.reference"))
        dims.update(_read_dims(vt, f"variants.{variant}"))
    for key, value in overrides.items():
        if key not in dims:
            raise InputError(f"{key} is not a dimension of {name}; dimensions: {', '.join(dims)}")
        dims[key] = Dimension(check_range(key, value), dims[key].unit, "override")
    density = _read_dims(data.get("material", {}), "material")["density"].value
    part = PartDef(name=name, kind=data["part"]["kind"], dims=dims, density=density,
                   description=data["part"].get("description", ""), path=path,
                   reference=reference)
    validate(part)
    return part


def _positive(part: PartDef, *keys: str) -> None:
    for k in keys:
        check_range(k, part[k], 0.0, None, "mm", lo_open=True)


def _need(cond: bool, msg: str) -> None:
    if not cond:
        raise InputError(msg)


def envelope_mm3(part: PartDef) -> float | None:
    """Volume of the box (plate: cylinder) that encloses the part, mm^3, from its dimensions
    alone: what a mesh will cost is known before any geometry is built.  None for a custom part."""
    if part.kind == "rail":
        return part["length"] * part["width"] * part["height"]
    if part.kind == "iprofile":
        return part["length"] * part["flange_width"] * part["height"]
    if part.kind == "plate":
        return math.pi / 4 * part["diameter"] ** 2 * max(part["thickness"], part["seat_width"])
    return None


def rail_hole_count(part: PartDef) -> int:
    """How many mounting holes a rail has: at first_offset + i*pitch up to L - first_offset."""
    L, a, p = part["length"], part["first_offset"], part["pitch"]
    return max(int(math.floor((L - 2 * a) / p + 1e-9)) + 1, 0)


def rail_hole_x(part: PartDef) -> np.ndarray:
    """x of every mounting hole of a rail, mm (:func:`rail_hole_count` of them)."""
    import numpy as np

    return part["first_offset"] + part["pitch"] * np.arange(rail_hole_count(part))


def rail_hole_groups(i: int) -> tuple[str, str, str]:
    """Surface groups of a rail's i-th hole (x order): through-bore, counterbore wall, counterbore floor.

    The one place rail hole names are made: geometry, loads, sweep and reports all call it.
    """
    return f"hole_{i:02d}", f"cbore_{i:02d}", f"cbore_floor_{i:02d}"


def rail_hole_name(i: int) -> str:
    """Group of a rail's i-th through-bore: where a screw's bearing load acts."""
    return rail_hole_groups(i)[0]


def validate(part: PartDef) -> None:
    """Raise InputError naming the dimension if the part cannot exist."""
    if part.kind == "rail":
        _positive(part, "length", "width", "height", "pitch", "first_offset", "hole_diameter",
                  "cbore_diameter", "cbore_depth")
        check_range("groove_radius", part["groove_radius"], 0.0, None, "mm")
        W, H, L = part["width"], part["height"], part["length"]
        rc = part["cbore_diameter"] / 2
        _need(part["hole_diameter"] < part["cbore_diameter"],
              f"hole_diameter = {part['hole_diameter']:g} mm must be smaller than cbore_diameter "
              f"= {part['cbore_diameter']:g} mm")
        _need(part["cbore_diameter"] <= W - 2 * MIN_WALL,
              f"cbore_diameter = {part['cbore_diameter']:g} mm is wider than the rail allows: "
              f"must be <= width - {2 * MIN_WALL:g} = {W - 2 * MIN_WALL:g} mm")
        _need(part["cbore_depth"] <= H - MIN_WALL,
              f"cbore_depth = {part['cbore_depth']:g} mm must be <= height - {MIN_WALL:g} "
              f"= {H - MIN_WALL:g} mm")
        _need(part["pitch"] >= part["cbore_diameter"] + MIN_WALL,
              f"pitch = {part['pitch']:g} mm must be >= cbore_diameter + {MIN_WALL:g} mm")
        _need(part["first_offset"] >= rc + MIN_WALL,
              f"first_offset = {part['first_offset']:g} mm must be >= cbore radius + {MIN_WALL:g} "
              f"= {rc + MIN_WALL:g} mm")
        _need(L >= 2 * part["first_offset"],
              f"length = {L:g} mm must be >= 2*first_offset = {2 * part['first_offset']:g} mm "
              f"(at least one hole)")
        rg = part["groove_radius"]
        if rg > 0:
            _need(W / 2 - rg - part["hole_diameter"] / 2 >= MIN_WALL,
                  f"groove_radius = {rg:g} mm cuts into the through-hole: must be <= "
                  f"{W / 2 - part['hole_diameter'] / 2 - MIN_WALL:g} mm")
            for k in ("groove_z_lower", "groove_z_upper"):
                z = check_range(k, part[k], rg + MIN_WALL, H - rg - MIN_WALL, "mm")
                _need(W / 2 - rg - rc >= MIN_WALL or z + rg < H - part["cbore_depth"] - MIN_WALL,
                      f"groove_radius = {rg:g} mm cuts into the counterbore at {k} = {z:g} mm")
            _need(part["groove_z_upper"] - part["groove_z_lower"] >= 2 * rg + MIN_WALL,
                  "groove_z_upper - groove_z_lower must be >= 2*groove_radius + 1 mm")
        ww = check_range("waist_width", part["waist_width"], 0.0, W, "mm")
        if ww > 0:
            _need(rg == 0, "waist_width and groove_radius cannot both be > 0 (choose one simplified profile)")
            za = check_range("waist_z_lower", part["waist_z_lower"], MIN_WALL, H - MIN_WALL, "mm")
            zb = check_range("waist_z_upper", part["waist_z_upper"], za, H - MIN_WALL, "mm", lo_open=True)
            _need(ww >= part["hole_diameter"] + 2 * MIN_WALL,
                  f"waist_width = {ww:g} mm cuts into the through-hole: must be >= "
                  f"{part['hole_diameter'] + 2 * MIN_WALL:g} mm")
            _need(ww >= part["cbore_diameter"] + 2 * MIN_WALL or zb <= H - part["cbore_depth"] - MIN_WALL,
                  f"waist_width = {ww:g} mm cuts into the counterbore: waist_z_upper = {zb:g} mm must be "
                  f"<= {H - part['cbore_depth'] - MIN_WALL:g} mm")
    elif part.kind == "plate":
        _positive(part, "diameter", "thickness", "bore_diameter", "seat_width", "hub_diameter",
                  "screw_spacing", "screw_diameter")
        R, rb, rh = part["diameter"] / 2, part["bore_diameter"] / 2, part["hub_diameter"] / 2
        s, rs = part["screw_spacing"] / 2, part["screw_diameter"] / 2
        _need(rb + MIN_WALL <= rh <= R,
              f"hub_diameter = {2 * rh:g} mm must lie in [bore_diameter + {2 * MIN_WALL:g}, "
              f"diameter] = [{2 * rb + 2 * MIN_WALL:g}, {2 * R:g}] mm")
        _need(s - rs >= rb + MIN_WALL,
              f"screw_spacing = {2 * s:g} mm puts the screw holes into the bearing bore: must be >= "
              f"{2 * (rb + MIN_WALL + rs):g} mm")
        _need(s + rs <= R - MIN_WALL,
              f"screw_spacing = {2 * s:g} mm puts the screw holes outside the disc: must be <= "
              f"{2 * (R - MIN_WALL - rs):g} mm")
        _need(part["thickness"] >= part["seat_width"] or s - rs >= rh + MIN_WALL,
              f"screw_spacing = {2 * s:g} mm puts the screw holes into the hub: hub_diameter = "
              f"{2 * rh:g} mm must be <= {2 * (s - rs - MIN_WALL):g} mm (or widen screw_spacing)")
    elif part.kind == "iprofile":
        _positive(part, "length", "flange_width", "height", "flange_thickness", "web_thickness",
                  "hole_diameter", "hole_spacing")
        b, tf, tw = part["flange_width"], part["flange_thickness"], part["web_thickness"]
        s, r = part["hole_spacing"] / 2, part["hole_diameter"] / 2
        _need(2 * tf + MIN_WALL <= part["height"],
              f"height = {part['height']:g} mm must be >= 2*flange_thickness + {MIN_WALL:g} mm")
        _need(tw <= b, f"web_thickness = {tw:g} mm must be <= flange_width = {b:g} mm")
        _need(2 * r <= part["length"] - 2 * MIN_WALL,
              f"hole_diameter = {2 * r:g} mm is wider than the profile length allows: must be <= "
              f"{part['length'] - 2 * MIN_WALL:g} mm")
        _need(s - r >= tw / 2 + MIN_WALL,
              f"hole_spacing = {2 * s:g} mm puts the holes into the web: must be >= "
              f"{2 * (tw / 2 + MIN_WALL + r):g} mm")
        _need(s + r <= b / 2 - MIN_WALL,
              f"hole_spacing = {2 * s:g} mm puts the holes outside the flange: must be <= "
              f"{2 * (b / 2 - MIN_WALL - r):g} mm")
        rf = check_range("fillet_radius", part["fillet_radius"], 0.0, None, "mm")
        _need(2 * rf + MIN_WALL <= part["height"] - 2 * tf,
              f"fillet_radius = {rf:g} mm does not fit the web's clear height: must be <= "
              f"{(part['height'] - 2 * tf - MIN_WALL) / 2:g} mm")
        _need(s - r >= tw / 2 + rf + MIN_WALL,
              f"fillet_radius = {rf:g} mm runs into the screw holes: must be <= "
              f"{s - r - tw / 2 - MIN_WALL:g} mm")
    elif part.kind != "custom":
        raise InputError(f"part kind {part.kind!r} is unknown; allowed: rail, plate, iprofile")
