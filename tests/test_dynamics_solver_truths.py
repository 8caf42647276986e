"""The dynamics solvers' edges (general inverse dynamics, closed-form toggles, the cycle entry points,
imported reactions, the 2013 model's toggle scan) against truths written without rigfem.

* A block driven along an inclined slide (a :class:`~rigfem.linkage.SliderDriver`): Newton's second
  law by hand, F = m (a − g) with a = s̈ u, the actuator's share F·u, and the moment about the sliding
  point (c − P) × F.
* A compressor without clearance (its piston reaches the cylinder head at top dead centre): the gas
  law's force is unbounded there (division by zero), so no finite reaction balances it; every other
  sample is the virtual work of the massless linkage, T = −F_x dx_B/dθ.
* A four-bar whose lengths fold flat (b2 + d = b3 + b4: a change point at crank 180°).
* The parallelogram four-bar (300/600/300/600 mm): its coupler translates and its rocker turns with the
  crank, so the transmission angle is the crank angle itself (μ = θ, 360° − θ past 180°) and the
  kinetic energy stays constant at constant crank speed: the crank torque is zero (energy balance);
  it folds flat at 0° and 180°, and the sample nearest each within one sample step is a toggle.
* Newton–Euler of the rig's four-bar (tests/newton_euler.py) for scripts' calls and an imported CSV.
* The law of cosines for where a four-bar's transmission angle crosses 5°, in closed form.
* The refusals the entry points document (their ranges, the mass model's linkage).
"""

import re
from collections.abc import Callable, Iterable

import numpy as np
import pytest
from newton_euler import fourbar_newton_euler

from rigfem.dynamics import compressor_gas_force, simulate, solve
from rigfem.dynamics.cycle import cycle_history
from rigfem.dynamics.history import DynamicsOptions
from rigfem.dynamics.imported import react
from rigfem.errors import ComputeError, InputError
from rigfem.io.reactions_csv import read_csv
from rigfem.linkage import GROUND, Body, Linkage, Prismatic, SliderDriver, crank_angles, four_bar, slider_crank
from rigfem.linkage.state import linkage_state

FINAL_CM = (480.0, 840.0, 780.0, 1020.0)
PARALLELOGRAM = (300.0, 600.0, 300.0, 600.0)


def _assert_newton_euler(h, lengths: tuple, speed_hz: float, rows: Iterable[int],
                         branch: Callable[[float], int] = lambda t: 1) -> None:
    """Every joint force and the torque of ``h`` at sample indices ``rows`` are Newton–Euler's (the
    four-bar's assembly ``branch`` at each crank angle: +1 open)."""
    for i in rows:
        t = float(h.crank_deg[i])
        F, T, _ = fourbar_newton_euler(*lengths, t, speed_hz, branch=branch(t))
        for n, f in F.items():
            assert np.allclose(h.joints[n].force_N[i], [f.real, f.imag], rtol=0, atol=1e-9), (n, t)
        assert h.torque_Nm[i] == pytest.approx(T, abs=1e-9), t


# ---- general inverse dynamics (rigfem.dynamics.inverse) ----

def test_a_block_driven_along_an_inclined_slide_is_newtons_second_law():
    """A 2 kg block on a slide at 30° through the origin, driven s = 200 + 50 sin θ mm at 1.5 Hz, under
    gravity; its centre of mass 50 mm above its frame origin, its sliding point P 100 mm behind it.
    The ground's force on the block (the slide's normal force plus the actuator's) is F = m (a − g),
    a = s̈ u; the actuator's force (the driver, in N) is F·u; the slide holds the block against the
    moment (c − P) × F about P."""
    u = np.array([np.cos(np.radians(30.0)), np.sin(np.radians(30.0))])
    lk = Linkage([Body("block", 2.0, (0.0, 50.0), 3000.0)],
                 [Prismatic("slide", GROUND, "block", (0.0, 0.0), tuple(u), (-100.0, 0.0))],
                 SliderDriver("slide", 200.0, 50.0), {"block": (200.0 * u[0] + 100.0, 200.0 * u[1], 0.0)},
                 gravity_mm_s2=(0.0, -9810.0))
    deg = crank_angles(12)
    h = solve(lk, deg, speed_hz=1.5)
    th, w = np.radians(deg), 2 * np.pi * 1.5
    s = 0.2 + 0.05 * np.sin(th)
    F = 2.0 * (-0.05 * w**2 * np.sin(th)[:, None] * u - np.array([0.0, -9.81]))
    c_minus_p = np.array([0.1, 0.05])
    assert (h.meta["solver"], h.meta["driver_unit"], h.meta["singular"]) == ("general", "N", None)
    slide = h.joints["slide"]
    assert (slide.name, slide.body_a, slide.body_b, slide.kind) == ("slide", GROUND, "block", "prismatic")
    assert np.allclose(slide.position_mm, 1000 * s[:, None] * u, rtol=0, atol=1e-9)
    assert np.allclose(slide.force_N, F, rtol=0, atol=1e-9)
    assert np.allclose(h.torque_Nm, F @ u, rtol=0, atol=1e-9)
    assert np.allclose(slide.moment_Nm, c_minus_p[0] * F[:, 1] - c_minus_p[1] * F[:, 0], rtol=0, atol=1e-9)


def test_a_compressor_without_clearance_is_a_toggle_at_top_dead_centre_in_the_general_solver():
    """Massless slider-crank 150/350 mm with the gas law of geometry/MECHANISMS.md §5 and L − c = 500 mm
    = b2 + b3: at crank 0° the piston reaches the head and the gas force is unbounded.  The general
    solver flags that sample alone (the builder's toggle test, rod near perpendicular, flags none) and
    gives its values as 0; every other sample is virtual work, T = −F_x dx_B/dθ, x_B = b2 cos θ + √(b3² −
    b2² sin² θ), F_x = −2000 N ((L − c − b3 + b2)/(L − c − x_B) − 1)."""
    b2, b3 = 150.0, 350.0
    lk = slider_crank(b2, b3, masses=None, slider_force=compressor_gas_force(b2, b3, L_mm=600.0, c_mm=100.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        h = solve(lk, crank_angles(36), speed_hz=20.0, general=True)
    assert h.meta["singular"] == [[0.0, 0.0]]
    assert np.array_equal(h.singular_mask, np.arange(36) == 0)
    assert all(np.array_equal(j.force_N[0], [0.0, 0.0]) for j in h.joints.values()) and h.torque_Nm[0] == 0.0
    th = np.radians(h.crank_deg[1:])
    root = np.sqrt(b3**2 - (b2 * np.sin(th)) ** 2)
    x = b2 * np.cos(th) + root
    dx = -b2 * np.sin(th) - b2**2 * np.sin(th) * np.cos(th) / root  # mm per rad
    fx = -2000.0 * ((500.0 - b3 + b2) / (500.0 - x) - 1.0)
    assert np.allclose(h.torque_Nm[1:], -fx * dx / 1000.0, rtol=1e-9, atol=1e-9 * np.abs(fx * dx).max() / 1000)


def test_the_general_solver_warns_where_a_four_bar_folds_flat():
    """540/840/780/1080 mm: b2 + d = b3 + b4, so the bars lie flat in line with the crank at 180°, where
    the two assembly branches meet; the general solver passes it and its history says so."""
    b2, b3, b4, d = 540.0, 840.0, 780.0, 1080.0
    assert b2 + d == b3 + b4
    h = solve(four_bar(b2, b3, b4, d), crank_angles(36), general=True)
    assert h.meta["solver"] == "general"
    assert "the linkage passes a toggle near crank angle 180.00 deg" in h.meta["warnings"]


# ---- closed-form toggles (rigfem.dynamics.closed) ----

@pytest.mark.parametrize("deg, flagged", [
    ([6.5, 96.5, 186.5, 276.5, 353.0], [6.5, 186.5]),   # 0° nearer the sample after it (6.5° < 7°)
    ([7.0, 97.0, 187.0, 277.0, 353.5], [187.0, 353.5]),  # 0° nearer the sample before it (6.5° < 7°)
], ids=["after", "before"])
def test_the_parallelogram_flags_the_sample_nearest_each_change_point(deg, flagged):
    """The parallelogram folds flat at 0° and 180°; sampled every 90° or so with no sample within 5° of
    either (μ = θ: none inside the builder's toggle band), the sample nearest each change point (within
    the largest step) is flagged, and only it.  The coupler translates, the rocker turns with the crank,
    the torque is zero (constant kinetic energy) and the forces are Newton–Euler's."""
    h = solve(four_bar(*PARALLELOGRAM), np.array(deg))
    assert h.meta["solver"] == "closed form"
    assert h.meta["singular"] == [[a, a] for a in flagged]
    assert np.array_equal(h.singular_mask, np.isin(deg, flagged))
    assert np.allclose(np.sin(h.bodies["coupler"].angle_rad), 0.0, atol=1e-12)
    assert np.allclose(np.exp(1j * h.bodies["rocker"].angle_rad), np.exp(1j * np.radians(deg)), atol=1e-12)
    assert np.allclose(h.torque_Nm, 0.0, atol=1e-9)
    _assert_newton_euler(h, PARALLELOGRAM, 1.0, range(len(deg)), branch=lambda t: 1 if t < 180 else -1)


def test_a_change_point_one_step_beyond_a_part_turn_flags_its_end_sample():
    """The parallelogram over 10°–170° every 10°: both change points lie exactly one step beyond an end
    (0° before 10°, 180° after 170°), so both end samples are flagged (μ = 10° there: not by the
    builder's band)."""
    h = solve(four_bar(*PARALLELOGRAM), np.arange(10.0, 180.0, 10.0))
    assert h.meta["singular"] == [[10.0, 10.0], [170.0, 170.0]]


def test_the_parallelograms_evaluator_at_one_and_two_crank_angles():
    """Re-solved at one angle (90°: far from both change points) the parallelogram is Newton–Euler's
    with zero torque and no toggle; at two (6.5° and 50°: one step of 43.5°) the sample 6.5° from the
    change point at 0° is flagged, 50° (130° from 180°) is not."""
    h = solve(four_bar(*PARALLELOGRAM), crank_angles(36))
    one = h.evaluator(np.array([90.0]))
    assert one.meta["singular"] is None and one.singular_mask is None
    _assert_newton_euler(one, PARALLELOGRAM, 1.0, [0])
    assert one.torque_Nm[0] == pytest.approx(0.0, abs=1e-9)
    two = h.evaluator(np.array([6.5, 50.0]))
    assert two.meta["singular"] == [[6.5, 6.5]]


# ---- a script's entry points (rigfem.dynamics.cycle) ----

def test_simulate_takes_a_linkage_described_as_a_dict_and_samples_every_degree_by_default():
    """simulate({"type": "four-bar", ...}) is the four-bar its builder makes (Newton–Euler at every
    sample); a turn is 360 samples, one per degree, unless told; a description without a known type
    is refused."""
    cfg = {"type": "four-bar", "b2": FINAL_CM[0], "b3": FINAL_CM[1], "b4": FINAL_CM[2], "d": FINAL_CM[3]}
    h = simulate(cfg, samples=12, speed_hz=1.3)
    assert h.meta["type"] == "four-bar" and np.array_equal(h.crank_deg, np.arange(12) * 30.0)
    _assert_newton_euler(h, FINAL_CM, 1.3, range(12))
    full = simulate(four_bar(*FINAL_CM))
    assert np.array_equal(full.crank_deg, np.arange(360.0))
    _assert_newton_euler(full, FINAL_CM, 1.0, [0, 90, 271])
    with pytest.raises(InputError, match="linkage type = None must be one of"):
        simulate({k: v for k, v in cfg.items() if k != "type"})
    with pytest.raises(InputError, match="linkage type = 'five-bar' must be one of"):
        simulate(dict(cfg, type="five-bar"))


def test_simulate_refuses_a_speed_out_of_range_and_the_2013_model_of_another_linkage():
    """The crank speed must be non-zero and within ±100 Hz; the 2013 model exists for the rig's
    four-bar only: asking it of a slider-crank is bad input (InputError), not a failure to compute."""
    for speed in (0.0, 150.0):
        with pytest.raises(InputError, match="speed_hz"):
            simulate(four_bar(*FINAL_CM), samples=12, speed_hz=speed)
    with pytest.raises(InputError, match=re.escape("not 'slider-crank' with masses 'rig'")):
        simulate(slider_crank(300.0, 840.0), samples=12, model="original")


@pytest.mark.parametrize("lk, what", [(lambda: four_bar(*FINAL_CM, masses=None), "'four-bar' with masses 'custom'"),
                                      (lambda: slider_crank(300.0, 840.0), "'slider-crank' with masses 'rig'")],
                         ids=["four-bar without masses", "slider-crank"])
def test_cycle_history_refuses_the_2013_model_of_any_linkage_but_the_rig_four_bar(lk, what):
    """cycle_history (the reactions stage's call, past the scene's checks) refuses the 2013 model of a
    four-bar without the rig's masses and of a slider-crank, naming what it was given."""
    lk = lk()
    deg = crank_angles(12)
    with pytest.raises(ComputeError, match=re.escape(f"model 'original' exists only for the four-bar with the "
                                                     f"rig masses, not {what}") + "$"):
        cycle_history(lk, linkage_state(lk, deg, 1.0), deg, 1.0, "original")


# ---- imported reactions (rigfem.dynamics.imported) ----

def test_an_imported_csv_on_a_change_point_four_bar_keeps_its_own_toggle_rows(tmp_path):
    """300/600/400/500 mm folds flat at crank 0° (b2 + b3 = b4 + d, d − b2 = b3 − b4).  A CSV of the
    Newton–Euler pin forces every 5° at 1.3 Hz, its row at 0° left blank and marked singular (the
    exact change point, where no finite force exists): the history's toggle ranges are the CSV's
    (not the wider band rigfem's own toggle test would give); its forces are the CSV's, at the joints
    as the linkage names them, its speed the scene's, its linkage the scene's."""
    lengths = (300.0, 600.0, 400.0, 500.0)
    pairs = {"O2": ("ground", "crank"), "A": ("crank", "coupler"), "B": ("coupler", "rocker"), "O4": ("ground", "rocker")}
    deg = np.arange(0.0, 360.0, 5.0)
    lines = [f"# joint {n}: force by {a} on {b}" for n, (a, b) in pairs.items()]
    lines.append("crank_deg," + ",".join(f"{n}_fx_N,{n}_fy_N" for n in pairs) + ",torque_Nm,singular")
    lines.append("0.0" + "," * 10 + "1")  # 8 force cells and the torque blank
    for t in deg[1:]:
        F, T, _ = fourbar_newton_euler(*lengths, t, 1.3)
        lines.append(",".join(repr(float(v)) for v in (t, *(x for n in pairs for x in (F[n].real, F[n].imag)), T)) + ",0")
    (tmp_path / "cp.csv").write_text("\n".join(lines) + "\n")
    lk = four_bar(*lengths)
    options = DynamicsOptions(speed_hz=1.3, reactions_csv=tmp_path / "cp.csv")
    r = react(lk, linkage_state(lk, crank_angles(360), 1.3), read_csv(tmp_path / "cp.csv"), options)
    h = r.history
    assert h.meta["singular"] == [[0.0, 0.0]] and r.singular == [[0.0, 0.0]] and r.summary["singular"] == [[0.0, 0.0]]
    assert (h.meta["speed_hz"], r.summary["speed_hz"]) == (1.3, 1.3)
    assert (r.summary["linkage"], r.summary["lengths_mm"]) == ("four-bar", dict(zip(("b2", "b3", "b4", "d"), lengths)))
    assert {n: (j.name, j.body_a, j.body_b) for n, j in h.joints.items()} == {n: (n, *p) for n, p in pairs.items()}
    _assert_newton_euler(h, lengths, 1.3, range(1, deg.size))
    assert all(r.peaks[n]["singular"] for n in ("O2", "A", "B", "O4", "torque"))


# ---- the 2013 model's toggle scan (rigfem.dynamics.original) ----

def test_the_2013_models_ranges_hold_a_flagged_sample_between_its_scan_points():
    """300/600/400/502 mm: sin μ < sin 5° for crank angles within θ_e of 0°, cos θ_e = (b2² + d² − b3² − b4²
    + 2 b3 b4 cos 5°) / (2 b2 d) (law of cosines), θ_e ≈ 4.72°.  Sampled every 5° from a sample between
    the last 0.1° scan point inside (4.7°) and θ_e: that sample is a toggle and a reported range holds
    it, beyond the scan's; every range lies inside the law's band, from 0° to the scan's last point."""
    b2, b3, b4, d = 300.0, 600.0, 400.0, 502.0
    edge = np.degrees(np.arccos((b2**2 + d**2 - b3**2 - b4**2 + 2 * b3 * b4 * np.cos(np.radians(5.0))) / (2 * b2 * d)))
    last = np.floor(edge * 10) / 10
    s = (last + edge) / 2
    deg = s + 5.0 * np.arange(72)
    lk = four_bar(b2, b3, b4, d)
    h = cycle_history(lk, linkage_state(lk, deg, 1.0), deg, 1.0, "original")
    near = np.minimum(deg % 360, 360 - deg % 360) < edge
    assert near[0] and near[-1] and near.sum() == 2
    assert np.array_equal(h.singular_mask, near)
    ranges = h.meta["singular"]
    assert all(any(a <= x <= b for a, b in ranges) for x in deg[near])
    assert all(min(x, 360 - x) < edge for r in ranges for x in r)
    assert ranges[0][0] == 0.0 and ranges[-1][1] == pytest.approx(359.9)


def test_the_closed_form_flags_an_unbounded_gas_force_as_the_general_solver_does():
    """The same compressor without clearance in closed form: only crank 0° (the piston at the head)
    is flagged, its values are 0, and every other sample is finite (inf and nan reached a
    reactions table before)."""
    lk = slider_crank(150.0, 350.0, masses=None,
                      slider_force=compressor_gas_force(150.0, 350.0, L_mm=600.0, c_mm=100.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        h = solve(lk, crank_angles(36), speed_hz=20.0)
    assert h.meta["solver"] == "closed form" and h.meta["singular"] == [[0.0, 0.0]]
    assert np.flatnonzero(h.singular_mask).tolist() == [0] and h.torque_Nm[0] == 0.0
    assert all(np.isfinite(j.force_N).all() for j in h.joints.values()) and np.isfinite(h.torque_Nm).all()
