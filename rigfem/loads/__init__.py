"""From a reaction history to per-part load cases: unit loads and their superposition weights.

The public API, loaded on first use (``lazy_loader``): importing one name does not
import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "cases": ["UnitLoad", "PartCase", "direction_weights", "directions", "rotate_into", "screw_forces", "Bar", "bar_body", "rail_angle", "cycle_rail", "part_cases"],
    },
)
