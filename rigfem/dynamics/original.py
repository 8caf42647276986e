"""Exact reproduction of the 2013 four-bar dynamics program (geometry/RIG.md §3), quirks included.

Closed-form four-bar kinematics at constant crank speed (:func:`fourbar_kinematics`, or the
linkage's motion as handed over: :func:`program_kinematics`), then per crank angle the
program's 9 linear equations (force balance of bars 2, 3, 4 and three moment
equations) for R12 (O2), R23 (A), R34 (B), R41 (O4) and the motor torque M2.
The quirks (guide mass given the acceleration of the *combined* centre of mass,
point masses added again, lever arms L3/2 and b3 - L3/2 on bar 3, no inertial
moment on bar 2, I_G3 = m3 b3^2/12 and I_O4 = m4 b4^2/3 from the joint distances)
are kept on purpose: this mode exists to reproduce the study's numbers.
Internal units SI (m, kg, s); the public results are in mm, N, N·m, degrees.
"""

from __future__ import annotations

import numpy as np

from rigfem.dynamics.history import (
    BodyHistory,
    JointHistory,
    ReactionHistory,
    merge_ranges,
)
from rigfem.linkage.loops import (
    MU_TOGGLE_DEG,
    fourbar_angles,
    singular_ranges,
    transmission_angle_deg,
)
from rigfem.linkage.mechanisms import crank_angles
from rigfem.linkage.model import GROUND, Linkage, LinkageState
from rigfem.rig.catalogue import RIG_MASSES, RIG_RAILS_MM, RigMasses

#: the 0.1 deg grid the 2013 model scans for toggles between the samples
TOGGLE_SCAN_DEG = crank_angles(3600)


def fourbar_kinematics(b2: float, b3: float, b4: float, d: float, theta2: np.ndarray, omega2: float,
                       branch: int = 1) -> dict[str, np.ndarray]:
    """Closed-form four-bar positions, velocities, accelerations (SI), O2 at 0, O4 at (d, 0),
    in the 2013 program's layout (the closed form itself: ``rigfem.linkage.kinematics``).

    ``branch`` = +1 is the open circuit (coupler turned counter-clockwise from A->O4),
    -1 the crossed one.  Angles in rad; raises ValueError where the loop cannot close.
    """
    th2 = np.asarray(theta2, dtype=float)
    k = fourbar_angles(b2, b3, b4, d, th2, omega2, 0.0, branch)
    if np.any(np.isnan(k["theta3"])):
        raise ValueError("four-bar loop cannot close at some crank angles")
    th3, th4 = k["theta3"], k["theta4"]
    return _layout(b2, b3, th2, omega2, th3, th4, k["omega3"], k["omega4"], k["alpha3"], k["alpha4"],
                   transmission_angle_deg(th3, th4))


def program_kinematics(motion: LinkageState, b2: float, b3: float, omega2: float) -> dict[str, np.ndarray]:
    """:func:`fourbar_kinematics`' dict (SI) of a four-bar's ``motion`` as the linkage layer gave it
    (:class:`~rigfem.linkage.model.LinkageState`: the same closed-form loop, or the general solver's
    motion near a toggle); ``b2``, ``b3`` in m."""
    c, r = motion.bodies["coupler"], motion.bodies["rocker"]
    return _layout(b2, b3, motion.theta, omega2, c.phi, r.phi, c.omega, r.omega, c.alpha, r.alpha, motion.mu_deg)


def _layout(b2, b3, th2, w2, th3, th4, w3, w4, a3, a4, mu_deg) -> dict[str, np.ndarray]:
    """The 2013 program's kinematics dict: angles, rates, mu (rad), A and B (O2 at 0)."""
    ax, ay = b2 * np.cos(th2), b2 * np.sin(th2)
    bx, by = ax + b3 * np.cos(th3), ay + b3 * np.sin(th3)
    return dict(theta2=th2, theta3=th3, theta4=th4, omega2=np.full_like(th2, w2), omega3=w3, omega4=w4,
                alpha2=np.zeros_like(th2), alpha3=a3, alpha4=a4, mu=np.radians(mu_deg),
                A=np.stack([ax, ay], -1), B=np.stack([bx, by], -1))


def original_reactions(b2_mm: float, b3_mm: float, b4_mm: float, d_mm: float, theta2: np.ndarray,
                       speed_hz: float = 1.0, masses: RigMasses = RIG_MASSES,
                       rails_mm: tuple[float, float, float] = RIG_RAILS_MM,
                       branch: int = 1) -> dict[str, np.ndarray]:
    """The 2013 program's reactions at crank angles ``theta2`` (rad).

    Returns forces in N as (n, 2) arrays, each the force exerted by the first-named
    body on the second: ``R12`` ground on crank at O2, ``R23`` crank on coupler at A,
    ``R34`` coupler on rocker at B, ``R14`` ground on rocker at O4; ``M2`` motor torque
    on the crank in N·m; plus the kinematics (``kin``) and transmission angle.
    """
    b2, b3, b4, d = (x / 1000.0 for x in (b2_mm, b3_mm, b4_mm, d_mm))
    k = fourbar_kinematics(b2, b3, b4, d, theta2, 2 * np.pi * speed_hz, branch)
    return program_reactions(k, b2_mm, b3_mm, b4_mm, speed_hz, masses, rails_mm)


def program_reactions(k: dict[str, np.ndarray], b2_mm: float, b3_mm: float, b4_mm: float,
                      speed_hz: float = 1.0, masses: RigMasses = RIG_MASSES,
                      rails_mm: tuple[float, float, float] = RIG_RAILS_MM) -> dict[str, np.ndarray]:
    """:func:`original_reactions` on the program's kinematics ``k`` (:func:`fourbar_kinematics`,
    :func:`program_kinematics`): the 9 equations per crank angle, quirks included."""
    b2, b3, b4 = (x / 1000.0 for x in (b2_mm, b3_mm, b4_mm))
    L2, L3, L4 = (x / 1000.0 for x in rails_mm)
    w2 = 2 * np.pi * speed_hz
    mr = masses.study_rail_kg_m
    m2, m3, m4 = mr * L2, mr * L3, mr * L4
    mp2 = masses.plate + masses.carriage        # at A on bar 2
    mA3 = masses.coupling                       # at A on bar 3
    mp3 = masses.plate + masses.carriage        # at B on bar 3
    mp4 = masses.coupling                       # at B on bar 4
    xg2 = (L2 / 2 * m2 + b2 * mp2) / (m2 + mp2)
    xg3 = (L3 / 2 * m3 + b3 * mp3) / (m3 + mp3)
    xg4 = (L4 / 2 * m4 + b4 * mp4) / (m4 + mp4)

    def unit(th):
        return np.stack([np.cos(th), np.sin(th)], -1)

    def perp(v):
        return np.stack([-v[..., 1], v[..., 0]], -1)

    u2, u3, u4 = unit(k["theta2"]), unit(k["theta3"]), unit(k["theta4"])
    w3, w4, a3, a4 = (k[n][..., None] for n in ("omega3", "omega4", "alpha3", "alpha4"))
    aA = -w2**2 * b2 * u2
    aG2 = -w2**2 * xg2 * u2
    aG3 = aA + a3 * xg3 * perp(u3) - w3**2 * xg3 * u3
    aB = aA + a3 * b3 * perp(u3) - w3**2 * b3 * u3
    aG4 = a4 * xg4 * perp(u4) - w4**2 * xg4 * u4
    F2 = m2 * aG2 + mp2 * aA
    F3 = m3 * aG3 + mA3 * aA + mp3 * aB
    F4 = m4 * aG4 + mp4 * aB
    I3 = m3 * b3**2 / 12 + mA3 * xg3**2 + mp3 * (b3 - xg3) ** 2
    I4 = m4 * b4**2 / 3 + mp4 * b4**2
    n = k["theta2"].shape[0]
    # unknowns: R12x R12y R23x R23y R34x R34y R14x R14y M2
    K = np.zeros((n, 9, 9))
    rhs = np.zeros((n, 9))
    # bar 2: R12 - R23 = F2 ;  M2 + (b2 u2) x (-R23) = 0
    K[:, 0, 0] = K[:, 1, 1] = 1.0
    K[:, 0, 2] = K[:, 1, 3] = -1.0
    rhs[:, 0:2] = F2
    r2 = b2 * u2
    K[:, 2, 8] = 1.0
    K[:, 2, 2] = r2[:, 1]       # -(r x R23) = -(rx R23y - ry R23x)
    K[:, 2, 3] = -r2[:, 0]
    # bar 3: R23 - R34 = F3 ; (-L3/2 u3) x R23 + ((b3 - L3/2) u3) x (-R34) = I3 a3
    K[:, 3, 2] = K[:, 4, 3] = 1.0
    K[:, 3, 4] = K[:, 4, 5] = -1.0
    rhs[:, 3:5] = F3
    ra, rb = -L3 / 2 * u3, (b3 - L3 / 2) * u3
    K[:, 5, 2], K[:, 5, 3] = -ra[:, 1], ra[:, 0]
    K[:, 5, 4], K[:, 5, 5] = rb[:, 1], -rb[:, 0]
    rhs[:, 5] = I3 * k["alpha3"]
    # bar 4: R34 + R14 = F4 ; (b4 u4) x R34 = I4 a4
    K[:, 6, 4] = K[:, 7, 5] = 1.0
    K[:, 6, 6] = K[:, 7, 7] = 1.0
    rhs[:, 6:8] = F4
    r4 = b4 * u4
    K[:, 8, 4], K[:, 8, 5] = -r4[:, 1], r4[:, 0]
    rhs[:, 8] = I4 * k["alpha4"]
    try:
        x = np.linalg.solve(K, rhs[..., None])[..., 0]
    except np.linalg.LinAlgError:  # a sample exactly at a change point: no finite reaction there (a toggle)
        x = np.full((n, 9), np.nan)
        for i in range(n):
            try:
                x[i] = np.linalg.solve(K[i], rhs[i])
            except np.linalg.LinAlgError:
                pass
    return dict(R12=x[:, 0:2], R23=x[:, 2:4], R34=x[:, 4:6], R14=x[:, 6:8], M2=x[:, 8],
                mu_deg=np.degrees(k["mu"]), kin=k)


def simulate_original(lk: Linkage, motion: LinkageState, deg: np.ndarray, speed_hz: float) -> ReactionHistory:
    """ReactionHistory of the 2013 program (rigfem.dynamics.original) for a four-bar Linkage on
    its ``motion`` at ``deg`` (the program's closed-form kinematics; the bodies' mass data);
    the evaluator and the toggle scan take the motion on the same branch (``motion.at``)."""
    L = lk.meta["lengths_mm"]
    b2, b3, b4, d = L["b2"], L["b3"], L["b4"], L["d"]
    bodies_tpl = motion.histories
    w2 = 2 * np.pi * speed_hz

    def build(m: LinkageState, a: np.ndarray, full_turn: bool = False) -> ReactionHistory:
        r = program_reactions(program_kinematics(m, b2 / 1000, b3 / 1000, w2), b2, b3, b4, speed_hz,
                              RigMasses(**lk.meta["catalogue"]), tuple(lk.meta["rails_mm"]))
        k = r["kin"]
        pos = {"O2": np.zeros((a.size, 2)), "A": k["A"] * 1000, "B": k["B"] * 1000,
               "O4": np.tile([d, 0.0], (a.size, 1))}
        joints = {"O2": JointHistory("O2", GROUND, "crank", r["R12"], pos["O2"]),
                  "A": JointHistory("A", "crank", "coupler", r["R23"], pos["A"]),
                  "B": JointHistory("B", "coupler", "rocker", r["R34"], pos["B"]),
                  "O4": JointHistory("O4", GROUND, "rocker", r["R14"], pos["O4"])}
        zero = np.zeros(a.size)
        aA = -(w2**2) * k["A"] * 1000
        bodies = {}
        for name, th, om, al, org, acc in (
                ("crank", k["theta2"], k["omega2"], zero, pos["O2"], np.zeros((a.size, 2))),
                ("coupler", k["theta3"], k["omega3"], k["alpha3"], pos["A"], aA),
                ("rocker", k["theta4"], k["omega4"], k["alpha4"], pos["O4"], np.zeros((a.size, 2)))):
            t = bodies_tpl[name]
            bodies[name] = BodyHistory(name, th, om, al, org, acc, t.mass_kg, t.com_local_mm,
                                       t.inertia_com_kg_mm2, t.point_masses, t.joint_local_mm)
        mu = r["mu_deg"]
        bad = np.sin(np.radians(mu)) < np.sin(np.radians(MU_TOGGLE_DEG))
        bad |= ~np.all(np.isfinite(np.c_[r["R12"], r["R23"], r["R34"], r["R14"], r["M2"]]), axis=1)
        meta = dict(lk.meta)
        meta.pop("singular_fn", None)
        meta.update(model="original", speed_hz=speed_hz, driver_unit="N·m",
                    mu_deg=dict(min=float(mu.min()), max=float(mu.max())),
                    singular=singular_ranges(a, bad))
        for j in joints.values():
            j.force_N = np.where(np.isfinite(j.force_N), j.force_N, 0.0)
        return ReactionHistory(a, joints, np.nan_to_num(r["M2"]), bodies, meta,
                               singular_mask=bad if bad.any() else None, full_turn=full_turn)

    def at(angles: np.ndarray) -> ReactionHistory:
        a = np.atleast_1d(np.asarray(angles, float))
        return build(motion.at(a), a)

    h = build(motion, deg, motion.full_turn)
    # toggles between the samples: the closed-form model is cheap on a 0.1 deg grid
    h.meta["singular"] = merge_ranges(h.meta["singular"], at(TOGGLE_SCAN_DEG).meta["singular"])
    h.evaluator = at
    return h


def original_program(b2_mm: float, b3_mm: float, b4_mm: float, d_mm: float, speed_hz: float = 1.0,
                     instants: int = 5000) -> dict[str, float]:
    """The 2013 program's printed figures: peak |R| of every pin, peak |M2|, mu min/max.

    Sampled exactly like the study: ``instants`` equally spaced crank angles over one turn
    (including both ends), no refinement.  Forces N, torque N·m, angles degrees.
    """
    th = np.linspace(0.0, 2 * np.pi, instants)
    r = original_reactions(b2_mm, b3_mm, b4_mm, d_mm, th, speed_hz)
    out = {name: float(np.max(np.hypot(r[key][:, 0], r[key][:, 1])))
           for name, key in (("O2", "R12"), ("A", "R23"), ("B", "R34"), ("O4", "R14"))}
    out["torque_Nm"] = float(np.max(np.abs(r["M2"])))
    out["mu_min_deg"] = float(np.min(r["mu_deg"]))
    out["mu_max_deg"] = float(np.max(r["mu_deg"]))
    return out
