"""Where couplings sit on a guide rail: hole positions and the coupling's screw spacing.

The loads (which holes a joint's screws go through) and the sweep (which joint distances
a rail can carry) both ask this one place.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from rigfem.errors import InfeasibleError
from rigfem.rig.parts import load_part, rail_hole_x


@dataclass(frozen=True)
class RailLayout:
    """Where couplings sit on a rail: hole positions and the coupling's screw spacing (mm)."""

    hole_x: np.ndarray  #: x of every mounting hole, increasing
    pitch: float
    screw_spacing: float  #: distance between a coupling's two screws (plate definition)

    @property
    def pivot_x(self) -> float:
        """The pivot joint: the first position whose coupling screws both land on holes."""
        return float(self.hole_x[0] + self.screw_spacing / 2)

    def _holes(self, distance_mm: float) -> tuple[int, int]:
        x = self.pivot_x + distance_mm
        lo = int(round((x - self.screw_spacing / 2 - self.hole_x[0]) / self.pitch))
        return lo, lo + int(round(self.screw_spacing / self.pitch))

    def fits(self, distance_mm: float) -> bool:
        """Whether a coupling ``distance_mm`` from the pivot lands both its screws on holes."""
        lo, hi = self._holes(distance_mm)
        return lo >= 0 and hi < len(self.hole_x)

    def coupling(self, distance_mm: float, bar: str) -> tuple[int, int]:
        """Hole indices of the two screws of the coupling ``distance_mm`` from the pivot.

        The joint is placed on the nearest position whose screws land on holes.
        """
        if not self.fits(distance_mm):
            most = self.hole_x[-1] - self.screw_spacing / 2 - self.pivot_x
            raise InfeasibleError(f"{bar}: a joint {distance_mm:g} mm from the pivot does not fit on a "
                                  f"{self.hole_x[-1] + self.hole_x[0]:g} mm rail; allowed 0..{most:g} mm "
                                  f"(choose a longer rail)")
        return self._holes(distance_mm)


@functools.lru_cache(maxsize=256)
def rail_layout(rail: str, length_mm: float, plate: str) -> RailLayout:
    """The layout of rail part ``rail`` cut to ``length_mm``, with couplings of plate ``plate``."""
    r = load_part(rail, {"length": length_mm})
    return RailLayout(rail_hole_x(r), r["pitch"], load_part(plate)["screw_spacing"])


@dataclass(frozen=True)
class RigPart:
    """One part instance of a linkage resolved against its definition (geometry/), once per check:
    what its load cases need besides the reactions."""

    part: str  #: part definition name
    kind: str  #: the definition's kind ("rail", "plate", "iprofile")
    layout: RailLayout  #: the rail it is, or the rail it is screwed to


def resolve_parts(parts: dict[str, dict], plate: str) -> dict[str, RigPart]:
    """The part instances ``parts`` (name -> spec, as ``rigfem.settings.PARTS``: a rail with its
    ``length``, a fitting with the spec of its ``rail``) resolved, couplings of plate ``plate``."""
    out = {}
    for name, spec in parts.items():
        rail = spec if "length" in spec else spec["rail"]
        out[name] = RigPart(spec["part"], load_part(spec["part"]).kind,
                            rail_layout(rail["part"], float(rail["length"]), plate))
    return out
