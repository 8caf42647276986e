"""Linear-elastic finite elements: model, assembly, loads, supports, solver, solution, stresses.

The public API, loaded on first use (``lazy_loader``): importing one name does not
import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "assembly": ["MIN_JACOBIAN", "FEMesh", "fe_mesh", "geometry", "volume", "element_dofs", "stiffness", "block_pattern"],
        "cache": ["solution_inputs", "check_energy", "peak_sweep", "cached_solve"],
        "forces": ["SurfaceForce", "Traction", "Pressure", "BearingLoad", "Torque", "BoltCircleTorque", "Gravity", "Inertia", "Load", "bearing_vector", "load_vector"],
        "model": ["Model", "LOCKING_NU", "build_model", "load_matrix", "export_data", "supported_stiffness", "free_block", "StaticProblem", "solve"],
        "partcase": ["mesh_job", "mesh_case", "part_geometries", "group_job", "supports_of", "fe_load", "relieved_cases", "imbalance", "lever_mm", "CaseResult", "solve_group", "finish"],
        "executor": ["Plan", "solve_cases"],
        "ladder": ["Judge", "best_shrink"],
        "solution": ["Peak", "Solution"],
        "solver": ["DIRECT_MAX_DOF", "SolverError", "pardiso", "LinearSolver"],
        "stress": ["quadrature_stress", "nodal_stress", "BAND_FACTOR", "error_band_pct", "zz_error"],
        "supports": ["Fixed", "FixedComponents", "Symmetry", "ShaftInHole", "FreeBody", "surface_nodes", "component_dofs", "rigid_modes", "shaft_terms", "constraints"],
    },
)
