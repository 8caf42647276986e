"""The forces on a linkage over a crank turn: inertia and external loads, the joint reactions
and driver torque (general inverse dynamics and the closed forms), the 2013 program and the
reaction histories with their peaks.  Builds on :mod:`rigfem.linkage` (geometry and motion).

The public API, loaded on first use (``lazy_loader``): importing one name does not
import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "history": ["JointHistory", "ReactionHistory", "DynamicsOptions", "Reactions", "reactions_of", "merge_ranges", "spline_evaluator", "peaks", "summary"],
        "forces": ["cross", "inertia_load", "applied", "body_loads", "compressor_gas_force", "loaded_linkage"],
        "cycle": ["MODELS", "simulate", "cycle_history", "react"],
        "original": ["fourbar_kinematics", "program_kinematics", "original_reactions", "program_reactions", "simulate_original", "original_program"],
        "closed": ["closed_reactions"],
        "solver": ["solve", "reactions"],
        "inverse": ["general_reactions"],
    },
)
