"""The rig itself: part definitions (geometry/), the catalogue of masses and rails, the rig rules.

The public API, loaded on first use (``lazy_loader``): importing one name does not
import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "catalogue": ["RigMasses", "RIG_MASSES", "RIG_RAILS_MM"],
        "layout": ["RailLayout", "rail_layout", "RigPart", "resolve_parts"],
        "parts": ["GEOMETRY_DIR", "PartDef", "known_parts", "load_part", "envelope_mm3", "rail_hole_count", "rail_hole_x", "rail_hole_groups", "rail_hole_name", "validate"],
        "rules": ["HOLE_PITCH_MM", "MIN_GROUND_MM", "MU_LIMITS_DEG", "transmission_angle_range", "fourbar_rules", "slider_crank_rules", "rules_for", "broken_rules", "standing"],
    },
)
