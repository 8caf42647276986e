"""Linear-elastic finite elements: model, assembly, loads, supports, solver, solution, stresses.

The public API, loaded on first use (``lazy_loader``): importing one name does not
import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "assembly": ["TET_EDGES", "TRI_EDGES", "NODE_BARY", "MIN_JACOBIAN", "FEMesh", "fe_mesh", "tet_quadrature", "tri_quadrature", "shape_values", "shape_dL", "bary_gradients", "geometry", "points_at", "volume", "element_dofs", "stiffness", "block_pattern"],
        "cache": ["solution_inputs", "check_energy", "peak_sweep", "cached_solve"],
        "forces": ["SurfaceForce", "Traction", "Pressure", "BearingLoad", "Torque", "BoltCircleTorque", "Gravity", "Inertia", "Load", "outward_normals", "bearing_vector", "torque_vector", "body_vector", "body_basis", "body_coefficients", "load_vector"],
        "model": ["Model", "LOCKING_NU", "build_model", "load_matrix", "ExportData", "export_data", "supported_stiffness", "free_block", "StaticProblem", "solve"],
        "partcase": ["CONCENTRATORS", "mesh_job", "mesh_case", "part_geometries", "group_job", "supports_of", "fe_load", "relieved_cases", "imbalance", "lever_mm", "CaseResult", "solve_group", "frame_rows", "finish"],
        "executor": ["Plan", "Sink", "solve_cases"],
        "ladder": ["Judge", "Step", "best_shrink", "next_step"],
        "solution": ["Peak", "Solution"],
        "solver": ["DIRECT_MAX_DOF", "METHODS", "SolverError", "default_method", "pardiso", "LinearSolver"],
        "stress": ["quadrature_stress", "element_node_stress", "nodal_stress", "BAND_FACTOR", "error_band_pct", "zz_error"],
        "supports": ["Fixed", "FixedComponents", "Symmetry", "ShaftInHole", "FreeBody", "Support", "surface_quadrature", "surface_nodes", "component_dofs", "rigid_modes", "shaft_terms", "shaft_springs", "three_two_one", "constraints"],
    },
)
