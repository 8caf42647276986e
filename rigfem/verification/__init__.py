"""Verification studies: mesh convergence, the error band's coverage, NAFEMS LE10, closed forms,
and the CalculiX cross-check.

Loaded on first use (``lazy_loader``): importing one name does not import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "convergence": ["RATIO", "EXTEND", "AWAY_MM", "TARGETS", "StepSpec", "StudySpec", "richardson", "h_levels", "run_step", "scene_cases", "study", "analyse",
                        "to_json"],
        "calculix": ["Comparison", "compare", "cross_check", "verify_job"],
        "closed_form": ["kt_plate_hole", "plate_hole_peak_mpa"],
        "le10": ["solve_le10"],
    },
)
