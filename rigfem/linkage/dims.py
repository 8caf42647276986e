"""The dimensions a linkage builder or a kinematics run is given, checked once as they are made.

The builders (:mod:`rigfem.linkage.mechanisms`) and the closed-form kinematics
(:mod:`rigfem.linkage.kinematics`) take raw numbers from Python scripts and the CLI; they wrap
them in these value types first, so the computation below trusts them.  Each refusal is one
InputError line naming the field, the value and the allowed range.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from rigfem.errors import InputError, check_range

BRANCH_NAMES = ("open", "crossed")
MASS_NAMES = ("rig", None)


@dataclass(frozen=True)
class Lengths:
    """Lengths (mm) by name, each finite and in [``lo``, ``hi``] mm: a builder's 10-10000 mm,
    where a value below 10 reads as metres given by mistake, or a kinematics run's (0, 1e5] mm
    (``lo`` = 0, open).  ``signed``: offsets, each within ±``hi``; ``arm``: a length that may be 0."""

    mm: dict[str, float]
    lo: float = 10.0
    hi: float = 10_000.0
    signed: dict[str, float] = field(default_factory=dict)
    arm: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for k, v in self.mm.items():
            if self.lo == 0:
                check_range(k, v, 0.0, self.hi, "mm", lo_open=True)
                continue
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v) or v <= 0:
                raise InputError(f"{k} = {v!r} mm must be a positive length in mm")
            if v < self.lo:
                raise InputError(f"{k} = {v:g} looks like metres: lengths are in mm "
                                 f"(allowed {self.lo:g} to {self.hi:g} mm)")
            if v > self.hi:
                raise InputError(f"{k} = {v:g} mm is outside the allowed range [{self.lo:g}, {self.hi:g}] mm")
        for k, v in self.signed.items():
            check_range(k, v, -self.hi, self.hi, "mm")
        for k, v in self.arm.items():
            check_range(k, v, 0.0, self.hi, "mm")


@dataclass(frozen=True)
class Rails:
    """The guide rails (mm) the bars of a rig linkage run on, one per bar (``bars``: name -> length
    mm, in order), each a valid length that reaches its bar's far joint from ``behind_mm`` behind
    the pivot."""

    rails_mm: tuple[float, ...]
    bars: dict[str, float]
    behind_mm: float

    def __post_init__(self) -> None:
        if len(self.rails_mm) != len(self.bars):
            raise InputError(f"rails_mm needs {len(self.bars)} lengths (mm), one per bar ({', '.join(self.bars)}); "
                             f"got {len(self.rails_mm)}")
        for i, ((name, b), L) in enumerate(zip(self.bars.items(), self.rails_mm)):
            Lengths({f"rails_mm[{i}]": L})
            if L - self.behind_mm < b:
                raise InputError(f"{name} = {b:g} mm does not fit on its rail: rails_mm[{i}] = {L:g} mm "
                                 f"reaches {L - self.behind_mm:g} mm past the pivot ({self.behind_mm:g} mm of it "
                                 f"lies behind); allowed {name} <= {L - self.behind_mm:g} mm")


@dataclass(frozen=True)
class Options:
    """A builder's choices: the assembly ``branch`` (open | crossed) and the ``masses`` ("rig": the
    rig's catalogue; None: massless unless given)."""

    branch: str = "open"
    masses: str | None = "rig"

    def __post_init__(self) -> None:
        if self.branch not in BRANCH_NAMES:
            raise InputError(f"branch = {self.branch!r} must be 'open' or 'crossed'")
        if self.masses not in MASS_NAMES:
            raise InputError(f"masses = {self.masses!r} must be 'rig' or none")


@dataclass(frozen=True)
class Drive:
    """The crank's angular velocity ``omega`` (rad/s, ±1e4) and acceleration ``alpha`` (rad/s², ±1e7)
    of a linkage of ``linkage_type`` (an acceleration only where a closed form takes it: the
    four-bar and the slider-crank; None: a closed form's own run)."""

    omega: float
    alpha: float = 0.0
    linkage_type: str | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "omega", check_range("omega", self.omega, -1e4, 1e4, "rad/s"))
        object.__setattr__(self, "alpha", check_range("alpha", self.alpha, -1e7, 1e7, "rad/s²"))
        if self.alpha != 0.0 and self.linkage_type not in (None, "four-bar", "slider-crank"):
            raise InputError(f"a driver acceleration (alpha = {self.alpha:g} rad/s²) is supported for the four-bar "
                             f"and slider-crank only, not {self.linkage_type!r}")
