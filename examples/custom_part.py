"""Your own part: a plate with a hole from a .geo file, meshed at a preset, pulled by a traction.

The part is ``plate_with_hole.geo`` (beside this file): 200 × 100 × 2 mm, a 20 mm hole at the
centre, its quarter y ≥ 0, z ≥ 0 built with the planes y = 0 and z = 0 as planes of symmetry.
The end x = 0 is held as a testing machine's grip would let it be: no axial motion, free to
contract (no false stress at the grip); the end x = 200 is pulled by a traction of 50 MPa.
The mesh uses the ``standard`` preset of a rig check (6 mm, 1.2 mm at the hole).  The peak von
Mises stress, with its error estimate, is compared with Peterson's Kt closed form.

Run: python examples/custom_part.py

Prints (tests/test_examples.py compares; ``...`` stands for what differs from run to run)::

    949 nodes (preset standard: 6 mm, 1.2 mm at the hole)
    peak von Mises 157.3 MPa ± 2.3 % (error estimate) on 'hole'
    Peterson Kt closed form 157.4 MPa: FE -0.11 %, within the error estimate
    41.9 % of σu/2 = 375 MPa: pass
"""

from pathlib import Path

from rigfem.fe import FixedComponents, Symmetry, Traction, build_model, solve
from rigfem.material import get_material
from rigfem.mesh import mesh_part
from rigfem.rig import load_part
from rigfem.settings import preset
from rigfem.verification.closed_form import plate_hole_peak_mpa
from rigfem.verdict import half_ultimate

SIGMA_MPA, WIDTH_MM, HOLE_MM = 50.0, 100.0, 20.0  # as in plate_with_hole.geo

steel = get_material("rig_steel")
plate = load_part(str(Path(__file__).with_name("plate_with_hole.geo")))
settings = preset("standard").refined(("hole",))  # the load-carrying surface gets the local size
pm = mesh_part(plate, settings)
model = build_model(pm, steel, order=settings.order)
supports = [FixedComponents("held", "x"), Symmetry("ysym"), Symmetry("zsym")]
sol = solve(model, supports, [Traction("loaded", (SIGMA_MPA, 0.0, 0.0))])  # MPa on the end face
peak = sol.peak()
exact = plate_hole_peak_mpa(SIGMA_MPA, WIDTH_MM, HOLE_MM)
diff = peak.value / exact - 1
band = peak.error_pct
print(f"{len(pm.points)} nodes (preset standard: {settings.size_mm:g} mm, {settings.near_mm:g} mm at the hole)")
print(f"peak von Mises {peak.value:.1f} MPa ± {band:.1f} % (error estimate) on '{peak.surface}'")
print(f"Peterson Kt closed form {exact:.1f} MPa: FE {100 * diff:+.2f} %, "
      + ("within the error estimate" if abs(100 * diff) <= band else "OUTSIDE the error estimate"))
v = half_ultimate(peak.value, steel.sigma_u, band)
print(f"{v.utilisation_pct:.1f} % of σu/2 = {v.limit_mpa:.0f} MPa: {v.verdict}")
