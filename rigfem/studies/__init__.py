"""Studies built on the check: mesh convergence, the CalculiX cross-check, the rig sweep.

The public API, loaded on first use (``lazy_loader``): importing one name does not
import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "band_coverage": ["CALIBRATION_SIZES", "CLOSED_FORMS", "PARTS", "PRESETS", "PART_CALIBRATION_STEPS", "preset_mesh", "closed_form_case", "part_cases", "required_factor", "inside", "calibrate", "run", "coverage", "markdown"],
        "cost": ["SECONDS_PER_ANGLE", "BYTES_PER_ANGLE", "JobCost", "turning", "bases_cost", "sweep_cost", "synthesis_cost", "check_cost"],
        "closed_form": ["kt_plate_hole", "plate_hole_peak_mpa"],
        "convergence": ["RATIO", "H_DIRECTIONS", "TARGETS", "NOISE", "AWAY_MM", "EXTEND", "Extrapolation", "richardson", "StepSpec", "away_from_singular_edges", "run_step", "h_levels", "preset_steps", "study", "needs_finer", "fine_step", "analyse", "scene_cases", "to_json"],
        "le10": ["INNER", "OUTER", "HALF_THICKNESS", "PRESSURE", "POINT_D", "TARGET_SYY", "STEEL", "SURFACES", "supports", "load", "le10_mesh", "node_at", "solve_le10"],
        "sweep_configs": ["TYPES", "GROUND_RAIL_MM", "ORIGINAL_DIRECTIONS", "TOP_NODES", "BOUND_GROUPS", "ROW_CHUNK", "JOINTS", "LENGTHS", "SweepParams", "rig_rail_layout", "rail_lengths", "enumerate_configs", "rules_row"],
        "sweep_bases": ["UnitBasis", "case_key", "mesh_ahead", "build_bases", "case_peak", "superposed_peaks"],
        "sweep": ["evaluate", "run_chunk", "run_sweep", "CONNECT_TIMEOUT_S", "check_scheduler", "reach_scheduler"],
        "shapes": ["FACES", "box", "gmsh_part", "faces_at", "plate_with_hole", "quarter_ring", "bar_with_holes"],
        "sweep_report": ["WORST", "FINAL_DESIGN", "write_maps", "worst_markdown", "write_report", "summary_html"],
        "rig_design": ["LENGTH_KEYS", "rig_fourbars", "snap_function", "snap_motion", "rule_table", "stress_verdicts"],
        "verify": ["Comparison", "compare", "cross_check", "verify_scene"],
    },
)
