"""The rig's catalogue: rail lengths and the point masses of plates, carriages and couplings (geometry/RIG.md §3)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class RigMasses:
    """The rig's mass catalogue (geometry/RIG.md §3): rails, carriage, plate, coupling (kg).

    ``rail_kg_m`` is the catalogue's linear mass (geometry/rail_size25.toml), used by the
    rigid-body model; ``study_rail_kg_m`` the 2013 study's, used by the original model.
    ``rail_behind_mm``: rail length behind a bar's first joint — the first hole's end distance
    (20 mm) plus half the coupling's screw spacing (60 mm), where the meshed rail's pivot sits
    (``rigfem.loads.cases.RailLayout.pivot_x``; a test keeps the two equal).
    """

    rail_kg_m: float = 3.1
    study_rail_kg_m: float = 2.7
    rail_behind_mm: float = 80.0
    carriage: float = 0.68
    plate: float = 1.155
    coupling: float = 0.577


#: the one mass catalogue of the rig
RIG_MASSES = RigMasses()


#: guide rail lengths of the final design (mm): crank, coupler, rocker
RIG_RAILS_MM = (700.0, 1000.0, 1000.0)
