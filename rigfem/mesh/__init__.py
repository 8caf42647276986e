"""The mesh of one part: gmsh/OpenCASCADE geometry, meshing, second-order nodes, the cache.

The public API, loaded on first use (``lazy_loader``): importing one name does not
import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "geometry": ["gmsh_session", "build", "occ_volume_mm3"],
        "volume": ["volume_mm3", "mass_kg"],
        "mesher": ["MACHINE_GIB", "TETS_PER_H3", "CURVATURE_MM", "MeshSettings", "curvature_n", "DEFAULT_SIZE", "Estimate", "estimate_tets", "estimate", "estimate_part", "check_estimate", "TETS_PER_S", "SMOOTHED_KINDS", "second_order", "mesh_part", "mesh_inputs", "make_mesh", "prefetch"],
        "pool": ["WORKERS", "submit", "take", "cancel"],
        "partmesh": ["Hole", "PartMesh", "fit_cylinder", "quality_summary", "save_npz", "load_npz", "TET10_EDGES", "TRI6_EDGES", "TET_FACES", "TET_FACE_OPPOSITE", "boundary_faces", "face_owners", "quadratic", "to_meshio", "write_mesh"],
    },
)
