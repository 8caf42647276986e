"""How a textbook linkage moves: geometry/MECHANISMS.md's four-bar with a coupler point.

Loads the built-in scene, solves positions, velocities and accelerations over one turn
with the general planar solver, and prints the transmission-angle range and the size of
the coupler curve.

Run: python examples/textbook_kinematics.py

Prints (tests/test_examples.py compares; ``...`` stands for what differs from run to run)::

    mech2-fourbar-coupler-point: transmission angle 12.2..96.1 deg over one turn
    coupler curve spans 166.6 x 115.0 mm
"""

import numpy as np

from rigfem.dynamics import loaded_linkage, simulate
from rigfem.linkage import coupler_point_path
from rigfem.scene import load_scene

scene = load_scene("mech2-fourbar-coupler-point")
h = simulate(loaded_linkage(scene), samples=360, speed_hz=scene.speed_hz)
mu = h.meta["mu_deg"]
path = coupler_point_path(h)
span = np.ptp(path, axis=0)
print(f"{scene.name}: transmission angle {mu['min']:.1f}..{mu['max']:.1f} deg over one turn")
print(f"coupler curve spans {span[0]:.1f} x {span[1]:.1f} mm")
