"""Part load cases: from a linkage's reaction history to unit loads and superposition weights.

Linear elasticity is linear, so every part is solved once per *unit* load and the stress at
any crank angle is ``σ(θ) = Σ_k c_k(θ) σ_k``.  A :class:`PartCase` holds the unit loads of one
part and the coefficient matrix ``coef`` (one row per crank angle, or per study case).

Bearing loads (a pin or screw pushing on the half of a hole, cosine pressure) are not linear
in the force *direction*, so a force that turns over the cycle is written as a non-negative
combination of the two neighbouring of ``n_dir`` fixed directions (:func:`direction_weights`):
the pressure then always lies on the side the force pushes.

Conventions (mm, N, N·mm, rad/s, mm/s²):

* A rail's frame is its mesh frame: x along the rail from its end, y across, z up; the
  linkage plane is x–y.  A coupling (plate + shaft) is screwed through two holes
  ``screw_spacing`` apart (the plate definition); its joint lies midway between them.  The
  pivot coupling uses the first holes of the rail (:class:`RailLayout`).
* ``original`` mode (2013 study): peak reaction × load factor at the far joint, split equally
  over the last two holes of the rail, in the rail's longitudinal/transverse directions; the
  rail is held by the two screws of its pivot coupling.
* ``cycle`` mode: at every crank angle the actual joint forces through the actual coupling
  holes, the driver torque as a screw couple, minus the inertia of the point masses lumped at
  each joint, plus the rail's own inertia as a body force; the bar is solved free.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rigfem.dynamics.history import BodyHistory, ReactionHistory
from rigfem.errors import ComputeError, InfeasibleError
from rigfem.rig.layout import RailLayout
from rigfem.rig.parts import rail_hole_name

#: inertia unit cases: body force -ρ·(a0 + α ẑ×r − ω² r) split into its linear parts
INERTIA = ("a0x", "a0y", "alpha", "omega2")


@dataclass(frozen=True)
class UnitLoad:
    """One unit load on a part, in the part's frame.

    ``kind="bearing"``: 1 N pushed by a pin/screw on hole ``group`` along ``direction``.
    ``kind="inertia"``: body force of unit ``component`` (one of :data:`INERTIA`) about the
    point ``direction`` (the reference point r = 0), density scaled so that the part's mass is
    ``PartCase.mass_kg``.
    """

    kind: str
    group: str | None = None
    direction: tuple[float, float, float] | None = None  #: bearing direction, or inertia origin
    component: str | None = None


@dataclass
class PartCase:
    """One part instance to check: what to mesh, how it is held, its unit loads and weights."""

    name: str  #: instance name, e.g. "crank_rail", "plate_A"
    part: str  #: part definition name (geometry/)
    params: dict  #: part parameters, e.g. {"length": 700}
    supports: list[tuple[str, tuple[str, ...]]]  #: [("bolt", ("hole_00", "hole_01"))] or [("free", ())]
    loads: list[UnitLoad]
    coef: np.ndarray  #: (n_rows, n_loads) weights of the unit solutions
    rows: np.ndarray  #: crank angle (deg) of each row
    refine: tuple[str, ...]  #: groups that carry load (mesh refinement)
    mass_kg: float | None = None  #: target mass for inertia loads
    notes: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.coef = np.atleast_2d(np.asarray(self.coef, dtype=float))
        if self.coef.shape != (len(self.rows), len(self.loads)):
            raise ValueError(f"{self.name}: coef shape {self.coef.shape} != "
                             f"({len(self.rows)}, {len(self.loads)})")
        if not np.all(np.isfinite(self.coef)):
            raise ComputeError(f"{self.name}: load coefficients contain NaN or infinity")


def direction_weights(v: np.ndarray, n_dir: int = 12) -> np.ndarray:
    """Non-negative weights (n, n_dir) with ``Σ_k w_k e_k = v`` on the two directions around v.

    ``e_k = (cos 2πk/n_dir, sin 2πk/n_dir)``; ``v`` has shape (n, 2).
    """
    v = np.atleast_2d(np.asarray(v, dtype=float))
    step = 2 * np.pi / n_dir
    ang = np.mod(np.arctan2(v[:, 1], v[:, 0]), 2 * np.pi)
    k0 = np.minimum(np.floor(ang / step).astype(int), n_dir - 1)
    k1 = (k0 + 1) % n_dir
    e0 = np.stack([np.cos(k0 * step), np.sin(k0 * step)], axis=1)
    e1 = np.stack([np.cos(k1 * step), np.sin(k1 * step)], axis=1)
    det = np.sin(step)
    a = (v[:, 0] * e1[:, 1] - v[:, 1] * e1[:, 0]) / det
    b = (e0[:, 0] * v[:, 1] - e0[:, 1] * v[:, 0]) / det
    w = np.zeros((v.shape[0], n_dir))
    rows = np.arange(v.shape[0])
    np.add.at(w, (rows, k0), np.maximum(a, 0.0))
    np.add.at(w, (rows, k1), np.maximum(b, 0.0))
    return w


def directions(n_dir: int) -> list[tuple[float, float, float]]:
    """The fixed in-plane unit directions used by :func:`direction_weights`."""
    t = 2 * np.pi * np.arange(n_dir) / n_dir
    return [(float(np.cos(a)), float(np.sin(a)), 0.0) for a in t]




def rotate_into(vectors: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Components of global in-plane vectors (n, 2) in frames turned by ``angle`` (n,) rad."""
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * vectors[:, 0] + s * vectors[:, 1],
                     -s * vectors[:, 0] + c * vectors[:, 1]], axis=1)


def screw_forces(force: np.ndarray, torque_nmm: np.ndarray | None, spacing_mm: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Forces (n, 2) on the two screws of a coupling (first at -spacing/2, second at +spacing/2 in x).

    The force is shared equally; a torque about z is carried as a couple ±T/spacing along y.
    """
    half = 0.5 * np.asarray(force, dtype=float)
    if torque_nmm is None:
        return half, half.copy()
    couple = np.zeros_like(half)
    couple[:, 1] = np.asarray(torque_nmm, dtype=float) / spacing_mm
    return half - couple, half + couple


def bearing_cases(hole_forces: dict[str, np.ndarray], n_dir: int
                  ) -> tuple[list[UnitLoad], np.ndarray]:
    """Unit bearing loads on each hole in ``n_dir`` directions and their weights (n, holes·n_dir)."""
    loads, cols = [], []
    dirs = directions(n_dir)
    for group, f in hole_forces.items():
        loads += [UnitLoad("bearing", group, d) for d in dirs]
        cols.append(direction_weights(f, n_dir))
    return loads, np.hstack(cols)


@dataclass(frozen=True)
class Bar:
    """A moving bar of the linkage built from a guide rail."""

    name: str  #: instance name, e.g. "crank_rail"
    pivot: str  #: joint at the rail's pivot coupling (its first holes)
    far: str  #: joint at the other coupling
    part: str  #: rail part definition
    length_mm: float
    layout: RailLayout
    length_between: float  #: joint-to-joint length b (mm)
    driven: bool = False  #: the crank: the driver torque enters through its pivot coupling


@dataclass(frozen=True)
class Fitting:
    """A plate or post at a joint, fixed to ``bar``'s rail and loaded by that joint's pin force."""

    name: str  #: e.g. "plate_A"
    part: str  #: "PF_4b_006", "PF_4b_003_v2"
    kind: str  #: "plate" or "iprofile"
    joint: str
    bar: Bar


def bar_body(h: ReactionHistory, bar: Bar) -> str:
    """The body that both of ``bar``'s joints belong to."""
    a, b = h.joints[bar.pivot], h.joints[bar.far]
    common = {a.body_a, a.body_b} & {b.body_a, b.body_b}
    if len(common) != 1:
        raise ComputeError(f"{bar.name}: joints {bar.pivot} and {bar.far} do not share exactly one body")
    return common.pop()


def force_on(h: ReactionHistory, joint: str, body: str) -> np.ndarray:
    """Force (n, 2) N that ``joint`` exerts on ``body`` (global frame)."""
    j = h.joints[joint]
    if body == j.body_b:
        return j.force_N
    if body == j.body_a:
        return -j.force_N
    raise ComputeError(f"joint {joint} does not act on body {body}")


def rail_angle(h: ReactionHistory, bar: Bar) -> np.ndarray:
    """Angle (n,) rad of the rail's x axis (pivot joint towards far joint) in the global frame."""
    p, q = h.joints[bar.pivot].position_mm, h.joints[bar.far].position_mm
    if p is None or q is None:  # every history a check makes has them (the scene gives the lengths)
        raise ComputeError(f"{bar.name}: the reaction history has no joint positions; give the "
                           f"linkage lengths in the scene so rigfem can place the rails")
    d = q - p
    return np.arctan2(d[:, 1], d[:, 0])


def _at_peak(h: ReactionHistory, peak: dict, what: str) -> tuple[ReactionHistory, float]:
    """The history evaluated at a refined peak's crank angles (every equal peak, e.g. the mirrored
    ones of a symmetric linkage: the study's case is then the worst of them), and the peak (N)."""
    if peak.get("singular") or peak.get("force_N") is None:
        raise InfeasibleError(f"{what}: the peak lies in a toggle (singular) range; no load can be "
                              f"derived — change the configuration")
    deg = np.asarray(peak.get("equal_peaks_deg") or [peak["crank_deg"]], float)
    if h.evaluator is not None:
        return h.evaluator(deg), float(peak["force_N"])
    idx = [int(np.argmin(np.abs((h.crank_deg - x + 180.0) % 360.0 - 180.0))) for x in deg]
    some = ReactionHistory(h.crank_deg[idx],
                           {n: type(j)(j.name, j.body_a, j.body_b, j.force_N[idx],
                                       None if j.position_mm is None else j.position_mm[idx])
                            for n, j in h.joints.items()},
                           h.torque_Nm[idx], None, h.meta)
    return some, float(peak["force_N"])


def _angles_text(deg: np.ndarray) -> str:
    """'12.34°', or '12.34° and 347.66° (equal peaks: the worst is checked)'."""
    text = " and ".join(f"{x:.2f}°" for x in deg)
    return text + (" (equal peaks: the worst is checked)" if len(deg) > 1 else "")


def _one_per_row(rows: int, per_row: int, value: float) -> list[list[float]]:
    """Coefficients of ``rows`` load sets of ``per_row`` unit loads each, one set per row."""
    return [[value if i * per_row <= j < (i + 1) * per_row else 0.0 for j in range(rows * per_row)]
            for i in range(rows)]


def _unit(v: np.ndarray) -> tuple[float, float, float]:
    n = float(np.hypot(*v))
    return (float(v[0] / n), float(v[1] / n), 0.0) if n > 0 else (1.0, 0.0, 0.0)


def _local_force(h: ReactionHistory, joint: str, bar: Bar, body: str) -> np.ndarray:
    return rotate_into(force_on(h, joint, body), rail_angle(h, bar))


def original_rail(h: ReactionHistory, pk: dict, bar: Bar, factor: float) -> PartCase:
    """The 2013 study's rail case: factor × peak far-joint reaction at the rail's far end."""
    at, mag = _at_peak(h, pk[bar.far], f"{bar.name} ({bar.far})")
    body = bar_body(h, bar)
    dirs = [_unit(v) for v in _local_force(at, bar.far, bar, body)]
    k = int(round(bar.layout.screw_spacing / bar.layout.pitch))
    last = len(bar.layout.hole_x) - 1
    screws = (rail_hole_name(last - k), rail_hole_name(last))
    pivot = tuple(rail_hole_name(i) for i in bar.layout.coupling(0.0, bar.name))
    f = factor * mag / 2
    return PartCase(bar.name, bar.part, {"length": bar.length_mm}, [("bolt", pivot)],
                    [UnitLoad("bearing", g, d) for d in dirs for g in screws], _one_per_row(len(dirs), 2, f),
                    np.array(at.crank_deg, float), pivot + screws,
                    notes=[f"{factor:g} × peak {bar.far} reaction {mag:.1f} N at crank "
                           f"{_angles_text(at.crank_deg)}, split over {screws[0]} and {screws[1]} at the "
                           f"far end (study's worst case); held by the screws of the pivot coupling"])


#: the I-profile rests on its base (no normal displacement, free to slide: no clamped-edge
#: singularity) and is bolted to the rail below through its bottom screws
POST_SUPPORTS = [("slide", ("base",)), ("bolt", ("screw_1", "screw_2"))]


POST_HELD = "base resting on the rail (normal displacement only), bottom screws bolted"


def original_fitting(h: ReactionHistory, pk: dict, fit: Fitting, factor: float,
                     iprofile_screw_load_n: tuple[float, float] = (250.0, 250.0)) -> PartCase:
    """The study's plate case (factor × peak pin reaction on the bore) or I-profile case."""
    if fit.kind == "iprofile":
        fl, ft = iprofile_screw_load_n
        screws = tuple(f"screw_{i}" for i in range(1, 5))
        mag = float(np.hypot(fl, ft))
        d = (fl / mag, ft / mag, 0.0)
        return PartCase(fit.name, fit.part, {}, POST_SUPPORTS,
                        [UnitLoad("bearing", s, d) for s in screws], [[mag] * 4], np.array([0.0]),
                        screws + ("fillets",), notes=[f"{fl:g} N longitudinal + {ft:g} N transverse at each screw "
                                       f"hole (study); {POST_HELD}"])
    at, mag = _at_peak(h, pk[fit.joint], f"{fit.name} ({fit.joint})")
    dirs = [_unit(v) for v in _local_force(at, fit.joint, fit.bar, bar_body(h, fit.bar))]
    return PartCase(fit.name, fit.part, {}, [("bolt", ("screw_1", "screw_2"))],
                    [UnitLoad("bearing", "bore", d) for d in dirs], _one_per_row(len(dirs), 1, factor * mag),
                    np.array(at.crank_deg, float), ("bore", "screw_1", "screw_2"),
                    notes=[f"{factor:g} × peak {fit.joint} pin reaction {mag:.1f} N at crank "
                           f"{_angles_text(at.crank_deg)} on the bearing seat; held by its two screws"])


def _point_acc(b: BodyHistory, local_mm: np.ndarray) -> np.ndarray:
    """Acceleration (n, 2) mm/s² of a point fixed in body ``b`` at ``local_mm``."""
    c, s = np.cos(b.angle_rad), np.sin(b.angle_rad)
    r = np.stack([c * local_mm[0] - s * local_mm[1], s * local_mm[0] + c * local_mm[1]], axis=1)
    perp = np.stack([-r[:, 1], r[:, 0]], axis=1)
    return b.origin_acc_mm_s2 + perp * b.alpha_rad_s2[:, None] - r * (b.omega_rad_s ** 2)[:, None]


def _coupling_force(h: ReactionHistory, joint: str, body: str) -> np.ndarray:
    """Force (n, 2) N through a coupling's screws: pin force minus the inertia of its point masses."""
    f = force_on(h, joint, body).copy()
    b = h.bodies[body]
    for label, m, local in b.point_masses:
        if label == joint:
            f -= m * _point_acc(b, np.asarray(local, float)) / 1000.0
    return f


def cycle_rail(h: ReactionHistory, bar: Bar, n_dir: int) -> PartCase:
    """A rail analysed free at every crank angle: coupling forces, driver torque, own inertia."""
    if h.bodies is None:  # every history a check makes has them (an imported CSV's: the linkage's)
        raise ComputeError(f"{bar.name}: cycle mode needs the bodies' motion; an imported reaction "
                           f"CSV has none — use original mode")
    body = bar_body(h, bar)
    phi = rail_angle(h, bar)
    hole_forces: dict[str, np.ndarray] = {}
    for joint in (bar.pivot, bar.far):
        x = 0.0 if joint == bar.pivot else bar.length_between
        torque = h.torque_Nm * 1000.0 if (joint == bar.pivot and bar.driven) else None
        lo, hi = bar.layout.coupling(x, bar.name)
        fa, fb = screw_forces(rotate_into(_coupling_force(h, joint, body), phi), torque,
                              bar.layout.screw_spacing)
        hole_forces[rail_hole_name(lo)] = fa
        hole_forces[rail_hole_name(hi)] = fb
    loads, coef = bearing_cases(hole_forces, n_dir)
    b = h.bodies[body]
    a0 = rotate_into(_point_acc(b, b.joint_local_mm[bar.pivot]), phi)
    origin = (bar.layout.pivot_x, 0.0, 0.0)
    loads += [UnitLoad("inertia", None, origin, c) for c in INERTIA]
    coef = np.hstack([coef, a0, b.alpha_rad_s2[:, None], (b.omega_rad_s ** 2)[:, None]])
    return PartCase(bar.name, bar.part, {"length": bar.length_mm}, [("free", ())], loads, coef,
                    h.crank_deg, tuple(hole_forces), mass_kg=b.mass_kg,
                    notes=[f"free body at every crank angle: joints {bar.pivot} and {bar.far} through "
                           f"their coupling screws ({', '.join(hole_forces)}), point-mass inertia "
                           f"removed from the pin forces, rail inertia as a body force "
                           f"({b.mass_kg:.3f} kg)"])


def cycle_fitting(h: ReactionHistory, fit: Fitting, n_dir: int) -> PartCase:
    """A plate (bore load) or I-profile (top screws) under the pin force at every crank angle."""
    f = _local_force(h, fit.joint, fit.bar, bar_body(h, fit.bar))
    if fit.kind == "iprofile":
        # the post's y axis lies along the rail (its screws go into two rail holes): x_p = -y_rail
        f = np.stack([-f[:, 1], f[:, 0]], axis=1)
        loads, coef = bearing_cases({"screw_3": f / 2, "screw_4": f / 2}, n_dir)
        return PartCase(fit.name, fit.part, {}, POST_SUPPORTS, loads, coef, h.crank_deg,
                        ("screw_1", "screw_2", "screw_3", "screw_4", "fillets"),
                        notes=[f"{fit.joint} pin force through the top screws; {POST_HELD}"])
    loads, coef = bearing_cases({"bore": f}, n_dir)
    return PartCase(fit.name, fit.part, {}, [("bolt", ("screw_1", "screw_2"))], loads, coef,
                    h.crank_deg, ("bore", "screw_1", "screw_2"),
                    notes=[f"{fit.joint} pin force on the bearing seat at every crank angle; held by "
                           f"its two screws"])


def _bar(name: str, spec: dict, h: ReactionHistory, layout: RailLayout) -> Bar:
    p, q = h.joints[spec["pivot"]].position_mm, h.joints[spec["far"]].position_mm
    b = float(np.hypot(*(q[0] - p[0]))) if p is not None and q is not None else 0.0
    return Bar(name, spec["pivot"], spec["far"], spec["part"], float(spec["length"]), layout, b,
               bool(spec.get("driven")))


def part_cases(h: ReactionHistory, pk: dict, settings) -> list[tuple[str, PartCase]]:
    """Every (mode, PartCase) a check solves, for the parts and modes of ``settings``.

    ``settings`` is a :class:`rigfem.settings.CheckSettings`, its parts resolved (``settings.rig``:
    layouts, kinds) once; ``pk`` the peaks of ``h``.
    """
    out = []
    for name, spec in settings.parts.items():
        rig = settings.rig[name]
        for mode in settings.modes:
            if "length" in spec:
                bar = _bar(name, spec, h, rig.layout)
                case = (original_rail(h, pk, bar, settings.load_factor) if mode == "original"
                        else cycle_rail(h, bar, settings.bearing_directions))
            else:
                fit = Fitting(name, spec["part"], rig.kind, spec["joint"], _bar(spec["on"], spec["rail"], h, rig.layout))
                case = (original_fitting(h, pk, fit, settings.load_factor) if mode == "original"
                        else cycle_fitting(h, fit, settings.bearing_directions))
            out.append((mode, case))
    return out
