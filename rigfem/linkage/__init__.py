"""The linkage apart from its dynamics: geometry and motion of planar one-degree-of-freedom
linkages — loop closures, closed-form kinematics, branches and limit positions, synthesis,
the catalogue of mechanisms and the general planar solver's motion.  Nothing here imports
:mod:`rigfem.dynamics`: a kinematics or synthesis run needs no forces.

The public API, loaded on first use (``lazy_loader``): importing one name does not
import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "closed": ["closed_motion"],
        "state": ["linkage_state"],
        "loops": ["BRANCHES", "MU_TOGGLE_DEG", "transmission_angle_deg", "fourbar_closes", "fourbar_angles", "singular_ranges", "is_full_turn"],
        "kinematics": ["Motion", "fourbar_motion", "grashof_class", "fourbar_turn", "slider_crank_motion", "slider_crank_turn", "motion_from_history", "linkage_motion", "linkage_turn"],
        "model": ["GROUND", "ClosureError", "AssemblyError", "BodyHistory", "Body", "Revolute", "Prismatic", "CrankDriver", "SliderDriver", "Load", "Linkage", "BodyState", "LinkageState"],
        "mechanisms": ["four_bar", "transmission_angle", "coupler_point_path", "slider_crank", "inverted_slider_crank", "quick_return", "BUILDERS", "build", "crank_angles"],
        "general": ["RCOND_SINGULAR", "move"],
        "expression": ["parse_function"],
        "synthesis": ["chebyshev_points", "synthesize_function", "three_position", "crank_in_order", "check_three_position", "optimise_three_position"],
    },
)
