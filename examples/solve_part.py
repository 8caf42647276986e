"""Solve one part with your own load: the coupling plate, 2 kN on its bearing seat.

Meshes the plate (gmsh, second order), holds it by its two screws as the rig does (an
elastic shaft-in-hole support, no false singularity), pushes the bearing seat with a
cosine bearing pressure, and prints the peak von Mises stress against the allowable.

Run: python examples/solve_part.py

Prints (tests/test_examples.py compares; ``...`` stands for what differs from run to run)::

    4862 nodes; peak von Mises 31.6 MPa ± 7.2 % (error estimate) on 'screw_2' at [57.0, -0.0, 10.0] mm
    8.4 % of σu/2 = 375 MPa: pass
"""

from rigfem.fe import BearingLoad, ShaftInHole, build_model, solve
from rigfem.material import get_material
from rigfem.mesh import mesh_part
from rigfem.rig import load_part
from rigfem.settings import preset
from rigfem.verdict import half_ultimate

steel = get_material("rig_steel")
plate = load_part("PF_4b_006")
pm = mesh_part(plate, preset("standard").refined(("bore", "screw_1", "screw_2")))  # 6 mm, 1.2 mm there
model = build_model(pm, steel, order=preset("standard").order)
supports = [ShaftInHole("screw_1"), ShaftInHole("screw_2")]
sol = solve(model, supports, [BearingLoad("bore", (2000.0, 0.0, 0.0))])  # N, along x
peak = sol.peak()
v = half_ultimate(peak.value, steel.sigma_u, peak.error_pct)
print(f"{len(pm.points)} nodes; peak von Mises {peak.value:.1f} MPa ± {peak.error_pct:.1f} % (error estimate) "
      f"on '{peak.surface}' at {[round(float(t), 1) for t in peak.xyz]} mm")
print(f"{v.utilisation_pct:.1f} % of σu/2 = {v.limit_mpa:.0f} MPa: {v.verdict}")
