"""Motion and pin reactions over a crank turn: the general planar solver, the rig's linkages,
the textbook mechanisms and the 2013 program.

The public API, loaded on first use (``lazy_loader``): importing one name does not
import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "history": ["JointHistory", "BodyHistory", "ReactionHistory", "singular_ranges", "merge_ranges", "is_full_turn", "spline_evaluator", "peaks", "summary"],
        "loops": ["BRANCHES", "MU_TOGGLE_DEG", "transmission_angle_deg", "fourbar_closes", "fourbar_angles", "slider_crank_angles"],
        "kinematics": ["Motion", "fourbar_motion", "grashof_class", "fourbar_turn", "slider_crank_motion", "slider_crank_turn", "motion_from_history", "linkage_motion", "linkage_turn"],
        "linkage": ["GROUND", "ClosureError", "AssemblyError", "Body", "Revolute", "Prismatic", "CrankDriver", "SliderDriver", "Load", "Linkage"],
        "mechanisms": ["MODELS", "four_bar", "transmission_angle", "coupler_point_path", "slider_crank", "compressor_gas_force", "inverted_slider_crank", "quick_return", "BUILDERS", "crank_angles", "simulate", "simulate_original"],
        "original": ["fourbar_kinematics", "original_reactions", "original_program"],
        "closed": ["closed_form"],
        "solver": ["RCOND_SINGULAR", "STEP_CORRECTION", "SAMPLE_CORRECTION", "MIN_STEP", "solve"],
        "synthesis": ["parse_function", "chebyshev_points", "synthesize_function", "three_position", "crank_in_order", "check_three_position", "optimise_three_position"],
    },
)
