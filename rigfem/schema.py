"""The one schema of a scene file (pydantic v2): every table and key known, types strict,
ranges checked, NaN and infinity refused.

A scene file is read as raw TOML, validated here, and only then turned into plain scene data
(both in :mod:`rigfem.scene`) and check settings (:mod:`rigfem.settings`); CLI overrides of the
``[check]`` table go through the same :class:`CheckTable`.  Every problem becomes one
:class:`~rigfem.errors.InputError` line naming the field (``[check].order``), the value and
what is allowed; an unknown key gets a did-you-mean.  Units: mm, N, degrees, Hz, kg.
"""

from __future__ import annotations

import difflib
import re
from typing import Annotated, Literal, Union

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from rigfem.errors import InputError, plain
from rigfem.material import RELIABILITY, SURFACE
from rigfem.settings import FIDELITY, MODELS, MODES


class _Table(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=True)


Length = Annotated[float, Field(ge=10.0, le=10_000.0)]  # mm, as rigfem.linkage.mechanisms
Text = Annotated[str, Field(max_length=2000)]


class Body(_Table):
    """``[linkage.bodies.<name>]``: mass data of one body (with masses = "none")."""

    mass_kg: Annotated[float, Field(ge=0.0, le=1e4)] = 0.0
    com_local_mm: Annotated[list[Annotated[float, Field(ge=-1e4, le=1e4)]], Field(min_length=2, max_length=2)] = [0.0, 0.0]
    inertia_com_kg_mm2: Annotated[float, Field(ge=0.0, le=1e12)] = 0.0
    point_masses: Annotated[list[tuple[str, Annotated[float, Field(ge=0.0, le=1e4)],
                                       tuple[Annotated[float, Field(ge=-1e4, le=1e4)],
                                             Annotated[float, Field(ge=-1e4, le=1e4)]]]],
                            Field(max_length=20)] = []


class Gas(_Table):
    """``[linkage.gas]``: compressor gas force on a slider-crank's slider."""

    p_N: Annotated[float, Field(ge=0.0, le=1e6)] = 2000.0
    L_mm: Length = 1000.0
    c_mm: Annotated[float, Field(ge=0.0, le=10_000.0)] = 100.0


class CouplerPoint(_Table):
    distance_mm: Annotated[float, Field(ge=0.0, le=1e4)]
    angle_deg: Annotated[float, Field(ge=-360.0, le=360.0)]


class _Linkage(_Table):
    title: Text = ""
    notes: Text = ""
    masses: Literal["rig", "none"] = "rig"
    bodies: Annotated[dict[Annotated[str, Field(max_length=40)], Body], Field(max_length=10)] = {}
    instant_deg: Annotated[float, Field(ge=-360.0, le=360.0)] | None = None
    alpha_rad_s2: Annotated[float, Field(ge=-1e7, le=1e7)] = 0.0  #: crank angular acceleration
    textbook: bool = False  #: a textbook linkage (geometry/MECHANISMS.md), not a rig configuration
    speed_hz: Annotated[float, Field(ge=-100.0, le=100.0)] | None = None
    rpm: Annotated[float, Field(ge=-6000.0, le=6000.0)] | None = None
    omega_rad_s: Annotated[float, Field(ge=-100.0, le=100.0)] | None = None
    rails_mm: Annotated[list[Annotated[float, Field(ge=100.0, le=3000.0)]], Field(min_length=2, max_length=3)] | None = None

    @model_validator(mode="after")
    def _one_speed(self):
        given = [k for k in ("speed_hz", "rpm", "omega_rad_s") if getattr(self, k) is not None]
        if len(given) > 1:
            raise ValueError(f"give only one of speed_hz, rpm, omega_rad_s (got {', '.join(given)})")
        if given and getattr(self, given[0]) == 0:
            raise ValueError(f"{given[0]} = 0: the crank speed must be non-zero")
        if self.bodies and self.masses != "none":
            raise ValueError("[linkage.bodies] needs masses = 'none' (it replaces the rig catalogue)")
        return self


class FourBar(_Linkage):
    type: Literal["four-bar"]
    b2: Length
    b3: Length
    b4: Length
    d: Length
    branch: Literal["open", "crossed"] = "open"
    coupler_point: CouplerPoint | None = None


class SliderCrank(_Linkage):
    type: Literal["slider-crank"]
    b2: Length
    b3: Length
    offset: Annotated[float, Field(ge=-10_000.0, le=10_000.0)] = 0.0
    gas: Gas | None = None

    @model_validator(mode="after")
    def _clearance(self):
        """The gas force p (V1/V2 − 1) needs gas left at top dead centre: the cylinder head
        (L_mm − c_mm from the crank's pivot) beyond the piston's farthest reach."""
        if self.gas is not None:
            reach = max((self.b2 + self.b3) ** 2 - self.offset ** 2, 0.0) ** 0.5
            head = self.gas.L_mm - self.gas.c_mm
            if not head > reach:
                raise ValueError(f"[linkage.gas] L_mm - c_mm = {head:g} mm must exceed the piston's top dead "
                                 f"centre, sqrt((b2 + b3)^2 - offset^2) = {reach:g} mm: no gas is left to compress")
        return self


class InvertedSliderCrank(_Linkage):
    type: Literal["inverted-slider-crank"]
    d: Length
    b2: Length
    arm: Length


class QuickReturn(_Linkage):
    type: Literal["quick-return"]
    b2: Length
    pivot_below: Length
    ram_height: Length


LinkageTable = Annotated[Union[FourBar, SliderCrank, InvertedSliderCrank, QuickReturn],
                         Field(discriminator="type")]


class MaterialTable(_Table):
    """A user material in mm–N–MPa–t (ranges catch SI values given by mistake)."""

    name: Annotated[str, Field(min_length=1, max_length=60)]
    E: Annotated[float, Field(ge=1.0, le=1e7)]
    nu: Annotated[float, Field(ge=0.0, lt=0.5)]
    sigma_u: Annotated[float, Field(ge=0.01, le=1e5)]
    density: Annotated[float, Field(ge=0.0, le=1e-7)]


class Fatigue(_Table):
    """``[check.fatigue]``: the Goodman check's Marin factors."""

    surface: Literal[tuple(SURFACE)] = "machined"  # type: ignore[valid-type]
    reliability: Literal[tuple(RELIABILITY)] = 0.9  # type: ignore[valid-type]
    size_mm: Annotated[float, Field(ge=2.79, le=254.0)] = 19.0  # Shigley's size factor's range


class CsvMissing(_Table):
    """``[check.reactions_csv_missing]``: the value of a column the reactions CSV lacks, stated explicitly."""

    torque_Nm: Annotated[float, Field(ge=-1e5, le=1e5)]


class CheckTable(_Table):
    """``[check]``: what a check does (defaults: rigfem.settings and rigfem.check)."""

    modes: Annotated[list[Literal[MODES]], Field(min_length=1, max_length=2)] | None = None  # type: ignore[valid-type]
    parts: Annotated[list[Annotated[str, Field(min_length=1, max_length=40)]], Field(min_length=1, max_length=20)] | None = None
    fidelity: Literal[tuple(FIDELITY)] | None = None  # type: ignore[valid-type]
    order: Annotated[int, Field(ge=1, le=2)] | None = None
    size_mm: Annotated[float, Field(ge=0.1, le=100.0)] | None = None
    local_size_mm: Annotated[float, Field(ge=0.05, le=100.0)] | None = None
    adaptive: bool | None = None
    material: Annotated[str, Field(min_length=1, max_length=60)] | MaterialTable | None = None
    load_factor: Annotated[float, Field(gt=0.0, le=100.0)] | None = None
    limit_factor: Annotated[float, Field(gt=0.0, le=1.0)] | None = None
    bearing_directions: Annotated[int, Field(ge=4, le=72)] | None = None
    fatigue: Fatigue | None = None
    samples: Annotated[int, Field(ge=36, le=100_000)] | None = None
    mass_model: Literal[tuple(MODELS)] | None = None  # type: ignore[valid-type]
    frames: Annotated[int, Field(ge=0, le=360)] | None = None
    reactions_csv: Annotated[str, Field(min_length=1, max_length=1000)] | None = None
    reactions_csv_missing: CsvMissing | None = None

    @model_validator(mode="after")
    def _sizes(self):
        if self.reactions_csv_missing is not None and self.reactions_csv is None:
            raise ValueError("reactions_csv_missing is given without reactions_csv")
        if self.modes is not None and len(set(self.modes)) != len(self.modes):
            raise ValueError(f"modes = {self.modes} lists a mode twice")
        if self.size_mm is not None and self.local_size_mm is not None and self.local_size_mm > self.size_mm:
            raise ValueError(f"local_size_mm = {self.local_size_mm:g} must not exceed size_mm = {self.size_mm:g}")
        return self


class ReportTable(_Table):
    """``[report]``: what the report says beside the results (``rigfem check --author`` overrides it)."""

    author: Annotated[str, Field(max_length=200)] = ""


class SceneFile(_Table):
    """A whole scene file."""

    description: Text = ""
    linkage: LinkageTable
    check: CheckTable = CheckTable()
    report: ReportTable = ReportTable()


# ----------------------------------------------------------------------------- errors
def _field(loc: tuple) -> str:
    """pydantic location -> ``[check].order`` / ``[linkage.bodies.rod].mass_kg``."""
    parts = [str(p) for p in loc if not (isinstance(p, str) and p in _TAGS)]
    # drop the branch names pydantic adds for unions of types
    parts = [p for p in parts if not re.fullmatch(r"(float|int|str|list\[.*\]|tuple\[.*\]|constrained-\w+|"
                                                  r"literal\[.*\]|function-\w+\[.*\]|MaterialTable)", p)]
    tables, keys = [], list(parts)
    while keys and keys[0] in _TABLE_NAMES and (len(keys) > 1 or not tables):
        tables.append(keys.pop(0))
        if tables[-1] == "bodies" and keys:  # body name
            tables.append(keys.pop(0))
    head = f"[{'.'.join(tables)}]" if tables else ""
    tail = "".join(f"[{k}]" if k.isdigit() else f".{k}" for k in keys)
    return (head + tail).lstrip(".") or "scene"


_TAGS = {"four-bar", "slider-crank", "inverted-slider-crank", "quick-return"}
_TABLE_NAMES = {"linkage", "check", "report", "bodies", "gas", "fatigue", "coupler_point", "material"}


def _allowed(model: type[BaseModel] | None) -> list[str]:
    return sorted(model.model_fields) if model else []


def _model_at(loc: tuple, raw: dict) -> type[BaseModel] | None:
    """The schema table a location's parent belongs to (for did-you-mean)."""
    table = {"linkage": None, "check": CheckTable}
    if len(loc) <= 1:
        return SceneFile
    first = loc[0]
    if first == "linkage":
        typ = raw.get("linkage", {}).get("type") if isinstance(raw.get("linkage"), dict) else None
        lk = {"four-bar": FourBar, "slider-crank": SliderCrank,
              "inverted-slider-crank": InvertedSliderCrank, "quick-return": QuickReturn}.get(typ)
        rest = [p for p in loc[1:-1] if p not in _TAGS]
        if not rest:
            return lk
        return {"gas": Gas, "coupler_point": CouplerPoint, "bodies": Body}.get(str(rest[0]))
    if first == "check":
        rest = loc[1:-1]
        if not rest:
            return CheckTable
        return {"fatigue": Fatigue, "material": MaterialTable}.get(str(rest[0]))
    return table.get(first)


def _value(v) -> str:
    return plain(repr(v), 60)


def _message(e: dict, raw: dict) -> str:
    loc = tuple(e["loc"])
    where = _field(loc)
    if e["type"] == "extra_forbidden":
        key = str(loc[-1])
        allowed = _allowed(_model_at(loc, raw))
        near = difflib.get_close_matches(key, allowed, n=1, cutoff=0.6)
        hint = f"; did you mean {near[0]!r}?" if near else ""
        kind = "table" if isinstance(e["input"], dict) else "key"
        if len(loc) == 1:
            where = f"[{plain(key, 40)}]" if kind == "table" else plain(key, 40)
        return f"{where}: unknown {kind} {plain(key, 40)!r}{hint} " \
               f"(allowed: {', '.join(allowed)})"
    if e["type"] == "missing":
        return f"{where} is missing (required)"
    if e["type"] in ("union_tag_invalid", "union_tag_not_found"):
        return f"{where}.type = {_value(e['input'].get('type') if isinstance(e['input'], dict) else e['input'])} " \
               f"must be one of {', '.join(sorted(_TAGS))}"
    msg = plain(e["msg"].removeprefix("Value error, "), 160)
    if e["type"] == "value_error":
        return f"{where}: {msg}"
    return f"{where} = {_value(e['input'])}: {msg}"


def input_error(exc: ValidationError, raw: dict, prefix: str = "") -> InputError:
    """One InputError line from a pydantic error (the first problem, and how many more)."""
    errs = exc.errors(include_url=False)
    # of the union branches pydantic tried (str | table), report the one that fits the input
    first = max(errs, key=lambda e: len(e["loc"]))  # of a str | table union: the branch that fits
    more = f" (and {len(errs) - 1} more problem{'s' if len(errs) > 2 else ''})" if len(errs) > 1 else ""
    return InputError(f"{prefix}{_message(first, raw)}{more}")


def validate_scene(data: dict, name: str = "scene") -> SceneFile:
    """The raw TOML dict of a scene checked against :class:`SceneFile`."""
    try:
        return SceneFile.model_validate(data)
    except ValidationError as exc:
        raise input_error(exc, data, f"scene {plain(name, 80)!r}: ") from None
    except RecursionError:
        raise InputError(f"scene {plain(name, 80)!r} is nested too deeply") from None


def validate_check(table: dict, name: str = "scene") -> CheckTable:
    """A ``[check]`` table (the scene's merged with CLI overrides) checked against :class:`CheckTable`."""
    try:
        return CheckTable.model_validate(table)
    except ValidationError as exc:
        raw = {"check": table}
        errs = exc.errors(include_url=False)
        for e in errs:
            e["loc"] = ("check", *e["loc"])
        first = max(errs, key=lambda e: len(e["loc"]))
        more = f" (and {len(errs) - 1} more problem{'s' if len(errs) > 2 else ''})" if len(errs) > 1 else ""
        raise InputError(f"scene {plain(name, 80)!r}: {_message(first, raw)}{more}") from None
