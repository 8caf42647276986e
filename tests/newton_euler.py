"""Newton–Euler solutions of the rig's linkages written from geometry/RIG.md's data alone, the
independent truth tests/test_physics_truths.py and tests/test_limits.py hold rigfem's dynamics to.

Rigid-body model (geometry/RIG.md §3, rigfem's default): each bar is its guide rail, a uniform bar of
3.1 kg/m reaching 80 mm behind its pivot joint, plus point masses at its joints (plate +
carriage, coupling); the crank turns at constant speed; optional gravity.  Loop closure in
complex numbers, velocities and accelerations from the closure's derivatives, then one small
linear system per crank angle.  Nothing of rigfem is imported.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize_scalar

RAIL_KG_M = 3.1          # catalogue linear mass of the size-25 rail (geometry/RIG.md §3, §7)
BEHIND_MM = 80.0         # each rail reaches 80 mm behind its pivot joint (first hole 20 mm + half of 120 mm)
CARRIAGE, PLATE, COUPLING = 0.68, 1.155, 0.577  # geometry/RIG.md §3 mass catalogue, kg
RAILS_MM = (700.0, 1000.0, 1000.0)  # crank, coupler (rod), rocker guide rails (geometry/RIG.md §3)


def _cross(a: complex, b: complex) -> float:
    return a.real * b.imag - a.imag * b.real


def _bar(L_mm, particles, e, w, al, a_pivot, g):
    """A bar of rail length L with point masses [(kg, distance from its pivot m)]: Σ m (a − g) (N)
    and Σ r × m (a − g) + I_rail α about the pivot (N·m)."""
    m_rail = RAIL_KG_M * L_mm / 1000.0
    parts = [(m_rail, L_mm / 2000.0 - BEHIND_MM / 1000.0)] + particles
    acc = [a_pivot + s * (1j * al - w**2) * e for _, s in parts]
    force = sum(m * (a - g) for (m, _), a in zip(parts, acc))
    moment = sum(_cross(s * e, m * (a - g)) for (m, s), a in zip(parts, acc))
    return force, moment + m_rail * (L_mm / 1000.0) ** 2 / 12 * al


def fourbar_motion(b2, b3, b4, d, theta2_deg, speed_hz=1.0, branch=+1) -> dict:
    """The rig four-bar's motion at one crank angle (SI: m, rad/s, rad/s², m/s², complex x + iy):
    unit vectors ``e`` of the crank, coupler and rocker (O2→A, A→B, O4→B), their ``w`` and ``al``,
    the joints ``A``, ``B``, ``O4`` and the acceleration ``aA`` of A.  ``branch`` +1 is the open assembly."""
    b2, b3, b4, d = (x / 1000.0 for x in (b2, b3, b4, d))
    th2, w2, a2 = np.radians(theta2_deg), 2 * np.pi * speed_hz, 0.0
    e2 = np.exp(1j * th2)
    A, O4 = b2 * e2, complex(d, 0.0)
    D = O4 - A
    phi = np.arccos((b3**2 + abs(D) ** 2 - b4**2) / (2 * b3 * abs(D)))
    e3 = np.exp(1j * (np.angle(D) + branch * phi))
    B = A + b3 * e3
    e4 = (B - O4) / b4
    # closure b2 e2 + b3 e3 − b4 e4 = const: velocities, then accelerations ((iα − ω²) b e per bar)
    M = np.array([[(1j * b3 * e3).real, (-1j * b4 * e4).real], [(1j * b3 * e3).imag, (-1j * b4 * e4).imag]])
    rhs = -1j * b2 * w2 * e2
    w3, w4 = np.linalg.solve(M, [rhs.real, rhs.imag])
    rhs = -(1j * a2 - w2**2) * b2 * e2 + w3**2 * b3 * e3 - w4**2 * b4 * e4
    a3, a4 = np.linalg.solve(M, [rhs.real, rhs.imag])
    return {"e": (e2, e3, e4), "w": (w2, w3, w4), "al": (a2, a3, a4), "A": A, "B": B, "O4": O4,
            "aA": b2 * (1j * a2 - w2**2) * e2, "lengths": (b2, b3, b4)}


def fourbar_newton_euler(b2, b3, b4, d, theta2_deg, speed_hz=1.0, gravity=(0.0, 0.0), branch=+1,
                         rails_mm=RAILS_MM):
    """Pin forces (N, complex x + iy) and motor torque (N·m) of the rig four-bar at one crank angle.

    Forces: ``O2``/``O4`` of the ground on the crank/rocker, ``A`` of the crank on the coupler,
    ``B`` of the coupler on the rocker.  Also the joints' positions (mm, complex).  ``branch`` +1
    is the open assembly."""
    k = fourbar_motion(b2, b3, b4, d, theta2_deg, speed_hz, branch)
    (e2, e3, e4), (w2, w3, w4), (a2, a3, a4) = k["e"], k["w"], k["al"]
    A, B, O4 = k["A"], k["B"], k["O4"]
    b2, b3, b4 = k["lengths"]
    g = complex(*gravity) / 1000.0
    L2, L3, L4 = rails_mm
    crank = _bar(L2, [(PLATE + CARRIAGE, b2)], e2, w2, a2, 0, g)
    coupler = _bar(L3, [(COUPLING, 0.0), (PLATE + CARRIAGE, b3)], e3, w3, a3, k["aA"], g)
    rocker = _bar(L4, [(COUPLING, b4)], e4, w4, a4, 0, g)
    rA, rB3, rB4 = b2 * e2, b3 * e3, b4 * e4
    K = np.zeros((9, 9))  # unknowns O2x O2y Ax Ay Bx By O4x O4y T
    K[0, [0, 2]], K[1, [1, 3]], K[2, [2, 3, 8]] = (1, -1), (1, -1), (rA.imag, -rA.real, 1.0)  # crank: O2 − A
    K[3, [2, 4]], K[4, [3, 5]], K[5, [4, 5]] = (1, -1), (1, -1), (rB3.imag, -rB3.real)        # coupler: A − B
    K[6, [6, 4]], K[7, [7, 5]], K[8, [4, 5]] = (1, 1), (1, 1), (-rB4.imag, rB4.real)          # rocker: O4 + B
    f = np.array([v for F, m in (crank, coupler, rocker) for v in (F.real, F.imag, m)])
    x = np.linalg.solve(K, f)
    return ({"O2": complex(x[0], x[1]), "A": complex(x[2], x[3]), "B": complex(x[4], x[5]),
             "O4": complex(x[6], x[7])}, float(x[8]),
            {"O2": 0j, "A": A * 1000, "B": B * 1000, "O4": O4 * 1000})


def slider_crank_newton_euler(b2, b3, theta2_deg, speed_hz=1.0, gravity=(0.0, 0.0), rails_mm=RAILS_MM[:2]):
    """The rig slider-crank (no offset; geometry/RIG.md §1, masses of rigfem's builder docstring: plate +
    carriage at A on the crank, coupling at A and a plate at B on the rod, a carriage + coupling
    sliding at B): forces ``O2`` (ground on crank), ``A`` (crank on rod), ``B`` (rod on slider),
    ``slide`` (ground on slider, normal to the line), torque, positions."""
    b2, b3 = b2 / 1000.0, b3 / 1000.0
    th2, w2, a2 = np.radians(theta2_deg), 2 * np.pi * speed_hz, 0.0
    e2 = np.exp(1j * th2)
    A = b2 * e2
    e3 = np.exp(1j * np.arcsin(-A.imag / b3))   # B on the x axis, +x side
    B = A + b3 * e3
    w3 = -(b2 * w2 * e2.real) / (b3 * e3.real)  # Im(i ω b e) summed = 0 (B stays on the axis)
    aA = b2 * (1j * a2 - w2**2) * e2
    a3 = -(aA.imag - w3**2 * b3 * e3.imag) / (b3 * e3.real)
    aB = aA + b3 * (1j * a3 - w3**2) * e3
    g = complex(*gravity) / 1000.0
    crank = _bar(rails_mm[0], [(PLATE + CARRIAGE, b2)], e2, w2, a2, 0, g)
    rod = _bar(rails_mm[1], [(COUPLING, 0.0), (PLATE, b3)], e3, w3, a3, aA, g)
    slider = (CARRIAGE + COUPLING) * (aB - g)
    rA, rB = b2 * e2, b3 * e3
    K = np.zeros((8, 8))  # unknowns O2x O2y Ax Ay Bx By N T
    K[0, [0, 2]], K[1, [1, 3]], K[2, [2, 3, 7]] = (1, -1), (1, -1), (rA.imag, -rA.real, 1.0)  # crank: O2 − A
    K[3, [2, 4]], K[4, [3, 5]], K[5, [4, 5]] = (1, -1), (1, -1), (rB.imag, -rB.real)          # rod: A − B
    K[6, 4], K[7, [5, 6]] = 1, (1, 1)                                                         # slider: B + N
    f = np.array([crank[0].real, crank[0].imag, crank[1], rod[0].real, rod[0].imag, rod[1], slider.real, slider.imag])
    x = np.linalg.solve(K, f)
    return ({"O2": complex(x[0], x[1]), "A": complex(x[2], x[3]), "B": complex(x[4], x[5]), "slide": complex(0, x[6])},
            float(x[7]), {"O2": 0j, "A": A * 1000, "B": B * 1000})


def newton_euler_peak(solution, lengths, joint, speed_hz=1.0):
    """(peak |force| N, crank angle deg) of a joint over a turn: a 0.5° grid, then a bounded refinement."""
    f = lambda t: abs(solution(*lengths, t, speed_hz)[0][joint])  # noqa: E731
    grid = np.arange(0.0, 360.0, 0.5)
    t0 = grid[int(np.argmax([f(t) for t in grid]))]
    r = minimize_scalar(lambda t: -f(t), bounds=(t0 - 0.5, t0 + 0.5), method="bounded", options={"xatol": 1e-9})
    return -r.fun, float(r.x % 360.0)


STUDY_RAIL_KG_M = 2.7  # the 2013 study's rail linear mass (geometry/RIG.md §3)


def study_program(b2, b3, b4, d, theta2_deg, speed_hz=1.0, rails_mm=RAILS_MM, branch=+1):
    """The 2013 study's dynamics program at one crank angle, written from geometry/RIG.md §3's description,
    quirks included: each guide mass m_i = 2.7 kg/m · L_i is given the acceleration of the bar's
    combined centre of mass xG_i = (L_i/2 m_i + b_i mp_i)/(m_i + mp_i) (mp_i the point mass at its
    far end), the point masses are added again with their joints' accelerations; bar 3's moment
    balance about xG... with lever arms L3/2 (R23) and b3 − L3/2 (R34) and (m3 b3²/12 + coupling·xG3²
    + (plate + carriage)(b3 − xG3)²)·α3; bar 4 about O4 with (m4 b4²/3 + coupling·b4²)·α4; bar 2
    without inertial moment.  Returns the forces (N, complex): ``O2`` ground on crank, ``A`` crank
    on coupler, ``B`` coupler on rocker, ``O4`` ground on rocker, and the motor torque (N·m)."""
    k = fourbar_motion(b2, b3, b4, d, theta2_deg, speed_hz, branch)
    (e2, e3, e4), (w2, w3, w4), (_, a3, a4) = k["e"], k["w"], k["al"]
    b2, b3, b4 = k["lengths"]
    L2, L3, L4 = (x / 1000.0 for x in rails_mm)
    m2, m3, m4 = (STUDY_RAIL_KG_M * L for L in (L2, L3, L4))
    mp2, mA3, mp3, mp4 = PLATE + CARRIAGE, COUPLING, PLATE + CARRIAGE, COUPLING
    xg2, xg3, xg4 = ((L / 2 * m + b * mp) / (m + mp) for L, m, b, mp in ((L2, m2, b2, mp2), (L3, m3, b3, mp3),
                                                                      (L4, m4, b4, mp4)))
    aA = k["aA"]
    aB = aA + b3 * (1j * a3 - w3**2) * e3
    F2 = m2 * xg2 * (-(w2**2)) * e2 + mp2 * aA
    F3 = m3 * (aA + xg3 * (1j * a3 - w3**2) * e3) + mA3 * aA + mp3 * aB
    F4 = m4 * xg4 * (1j * a4 - w4**2) * e4 + mp4 * aB
    I3 = m3 * b3**2 / 12 + mA3 * xg3**2 + mp3 * (b3 - xg3) ** 2
    I4 = m4 * b4**2 / 3 + mp4 * b4**2
    rA3, rB3, rA2, rB4 = -L3 / 2 * e3, (b3 - L3 / 2) * e3, b2 * e2, b4 * e4
    K = np.zeros((9, 9))  # unknowns O2x O2y Ax Ay Bx By O4x O4y T
    K[0, [0, 2]], K[1, [1, 3]], K[2, [2, 3, 8]] = (1, -1), (1, -1), (rA2.imag, -rA2.real, 1.0)  # M2 + rA2 × (−A) = 0
    K[3, [2, 4]], K[4, [3, 5]] = (1, -1), (1, -1)
    K[5, [2, 3, 4, 5]] = (-rA3.imag, rA3.real, rB3.imag, -rB3.real)  # rA3 × A + rB3 × (−B) = I3 α3
    K[6, [4, 6]], K[7, [5, 7]], K[8, [4, 5]] = (1, 1), (1, 1), (-rB4.imag, rB4.real)  # rB4 × B = I4 α4
    f = np.array([F2.real, F2.imag, 0.0, F3.real, F3.imag, I3 * a3, F4.real, F4.imag, I4 * a4])
    x = np.linalg.solve(K, f)
    return ({"O2": complex(x[0], x[1]), "A": complex(x[2], x[3]), "B": complex(x[4], x[5]),
             "O4": complex(x[6], x[7])}, float(x[8]), {"O2": 0j, "A": k["A"] * 1000, "B": k["B"] * 1000,
                                                       "O4": k["O4"] * 1000})
