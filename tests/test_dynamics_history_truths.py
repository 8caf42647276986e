"""Reaction peaks (rigfem.dynamics.history) against truths written without rigfem (issue 39: the
dynamics package's mutants).

Each history here is a load written in closed form, sampled over a turn (or part of one) and
re-evaluated between its samples by the same formula (as the linkage solver re-evaluates itself),
or, as an imported CSV is, by the cubic spline through its samples.  The truths:

* the maximum of a shifted cosine ``a + b·cos(n(θ − θ0))`` is ``a + b`` at ``θ0 + k·360/n``; its
  equal maxima are counted by hand;
* a compact bump ``H·cos²(π(θ − c)/2w)`` (zero beyond ``|θ − c| = w``) peaks at ``c`` with ``H``;
  bumps farther apart than their widths are equal, separate peaks;
* a sawtooth (a slow rise and a fast fall, or the mirror) peaks at its apex;
* a constant peaks everywhere: every sampled angle is an equal peak;
* a load flat over an interval has one peak, not two;
* a toggle range stated by the history starts where it says, and one met between samples is
  where the evaluator flags it;
* DynamicsOptions accepts the ends of its ranges and refuses the values just outside them.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import pytest

from rigfem.dynamics.history import (
    DynamicsOptions,
    JointHistory,
    ReactionHistory,
    _distinct,
    peaks,
    summary,
)
from rigfem.errors import InputError
from rigfem.linkage.mechanisms import crank_angles

Load = Callable[[np.ndarray], np.ndarray]


def _history(deg: np.ndarray, forces: dict[str, Load], torque: Load, *, full_turn: bool,
             evaluate: bool = True, meta: dict | None = None, flag: Callable | None = None) -> ReactionHistory:
    """A history of joint forces (x component ``forces[name](θ)``, y component 0) and a torque, all
    in closed form of the crank angle θ (deg); with ``evaluate`` it re-evaluates the formulas
    between samples (counting its calls in ``evaluator.calls``: past 100 a refinement does not
    converge), and ``flag(θ)`` marks the angles it calls a toggle."""
    meta = dict(meta or {})
    calls: list[int] = []

    def at(a: np.ndarray) -> ReactionHistory:
        calls.append(1)
        if len(calls) > 100:
            raise RuntimeError("the refinement does not converge")
        a = np.atleast_1d(np.asarray(a, float))
        joints = {n: JointHistory(n, "ground", n, np.column_stack([f(a), np.zeros(a.size)])) for n, f in forces.items()}
        mask = flag(a) if flag is not None else None
        return ReactionHistory(a, joints, torque(a), None, meta,
                               singular_mask=mask if mask is not None and mask.any() else None)

    h = at(deg)
    calls.clear()
    at.calls = calls
    h.full_turn = full_turn
    h.evaluator = at if evaluate else None
    return h


def _cos(a: float, b: float, n: float, theta0: float) -> Load:
    """a + b·cos(n(θ − θ0)) (θ in deg)."""
    return lambda t: a + b * np.cos(np.radians(n * (t - theta0)))


def _bump(c: float, height: float, w: float) -> Load:
    """height·cos²(π(θ − c)/2w) for |θ − c| < w, else 0."""
    return lambda t: np.where(np.abs(t - c) < w, height * np.cos(np.pi * (t - c) / (2 * w)) ** 2, 0.0)


def _wrapped(x: float, y: float) -> float:
    """The angle between two crank angles (deg), round the turn."""
    return abs((x - y + 180.0) % 360.0 - 180.0)


def test_three_equal_narrow_peaks_are_all_found_and_the_first_is_the_peak():
    """Three equal bumps 20° apart on a baseline, sampled every 10° (the middle one at its apex,
    the others 0.5° off theirs): all three are equal peaks; |sin θ| peaks equally at 90° and 270°."""
    force = lambda t: 1.0 + _bump(10.5, 1.0, 6.0)(t) + _bump(30.0, 1.0, 6.0)(t) + _bump(50.5, 1.0, 6.0)(t)
    h = _history(crank_angles(36), {"J": force}, lambda t: np.sin(np.radians(t)), full_turn=True)
    pk = peaks(h)
    j, tq = pk["J"], pk["torque"]
    assert j["force_N"] == pytest.approx(2.0, rel=1e-12) and j["crank_deg"] == pytest.approx(10.5, abs=1e-5)
    assert j["equal_peaks_deg"] == pytest.approx([10.5, 30.0, 50.5], abs=1e-5)
    assert (j["fx_N"], j["fy_N"], j["singular"]) == (pytest.approx(2.0, rel=1e-12), 0.0, False)
    assert tq["peak"] == pytest.approx(1.0, rel=1e-12) and tq["value"] == pytest.approx(1.0, rel=1e-12)
    assert tq["crank_deg"] == pytest.approx(90.0, abs=1e-5)
    assert tq["equal_peaks_deg"] == pytest.approx([90.0, 270.0], abs=1e-5)


def test_a_peak_just_below_a_full_turn_is_reported_within_the_turn():
    """Peaks at 359.6° (found from the sample at 0°) are reported at 359.6°, not −0.4°: the force
    2 + cos 2(θ − 359.6°) peaks equally at 179.6° and 359.6°, the torque 1.5 + cos(θ − 359.6°)
    once, at 359.6° with 2.5 N·m."""
    h = _history(crank_angles(36), {"J": _cos(2.0, 1.0, 2.0, 359.6)}, _cos(1.5, 1.0, 1.0, 359.6), full_turn=True)
    pk = peaks(h)
    j, tq = pk["J"], pk["torque"]
    assert j["force_N"] == pytest.approx(3.0, rel=1e-12) and j["crank_deg"] == pytest.approx(179.6, abs=1e-5)
    assert j["equal_peaks_deg"] == pytest.approx([179.6, 359.6], abs=1e-5)
    assert tq["peak"] == pytest.approx(2.5, rel=1e-12) and tq["value"] == pytest.approx(2.5, rel=1e-12)
    assert tq["crank_deg"] == pytest.approx(359.6, abs=1e-5) and "equal_peaks_deg" not in tq


def test_a_zero_torque_peaks_at_every_sampled_angle():
    """A torque of zero (a CSV without one, stated as 0 N·m) is largest everywhere: its peak is 0
    N·m and every sampled angle is an equal peak, the first one the peak's."""
    deg = crank_angles(36)
    h = _history(deg, {"J": _cos(2.0, 1.0, 1.0, 100.0)}, lambda t: np.zeros(np.size(t)), full_turn=True)
    tq = peaks(h)["torque"]
    assert (tq["peak"], tq["value"], tq["crank_deg"]) == (0.0, 0.0, 0.0)
    assert tq["equal_peaks_deg"] == pytest.approx(list(deg), abs=1e-9)


def test_a_load_flat_over_zero_degrees_has_one_peak():
    """A force flat at 2 N from −0.00005° to 12° (falling at 0.1 N/° outside, to 1 N) has one peak,
    at an angle of its flat top; found from the samples at 0° and 10° it is still one."""
    def force(t):
        w = (np.asarray(t) + 180.0) % 360.0 - 180.0
        outside = np.maximum(-5e-5 - w, 0.0) + np.maximum(w - 12.0, 0.0)
        return np.maximum(2.0 - 0.1 * outside, 1.0)

    pk = peaks(_history(crank_angles(36), {"J": force}, _cos(0.0, 1.0, 1.0, 200.0), full_turn=True))
    assert pk["J"]["force_N"] == 2.0 and "equal_peaks_deg" not in pk["J"]
    assert _wrapped(pk["J"]["crank_deg"], 6.0) <= 6.0 + 5e-5


def test_sawtooth_peaks_at_their_apex():
    """A slow rise (0.1 N/°) and a fast fall (2 N/°) to an apex at 109°, and the mirror to an apex
    at 241°, both 0.9 of a sample spacing from the sample that finds them, peak at their apex with
    5 N; refining takes the rounds a bracket shrinking 8-fold needs, not more."""
    def saw(apex: float, left: float, right: float) -> Load:
        return lambda t: np.maximum(5.0 - np.where(t <= apex, left * (apex - t), right * (t - apex)), 1.0)

    h = _history(crank_angles(36), {"rise": saw(109.0, 0.1, 2.0), "fall": saw(241.0, 2.0, 0.1)},
                 _cos(0.0, 1.0, 1.0, 200.0), full_turn=True)
    pk = peaks(h)
    for name, apex in (("rise", 109.0), ("fall", 241.0)):
        assert pk[name]["force_N"] == pytest.approx(5.0, abs=1e-6)
        assert pk[name]["crank_deg"] == pytest.approx(apex, abs=1e-6)
    rounds = int(np.ceil(np.log(2 * 10.0 / 1e-7) / np.log(8))) + 1   # ±1 sample to 1e-7°, 8-fold a round
    assert len(h.evaluator.calls) <= 2 * (rounds + 1)


def test_a_turn_from_minus_180_to_180_reports_its_angles_as_sampled():
    """A history sampled from −180° to 180° (both ends: not an evenly spaced full turn) keeps its
    angles: 2 − cos 2(θ − 3°) peaks equally at −87° and 93°, reported at −87°; 2 + cos 2θ peaks
    equally at both ends and at 0°, reported at the smallest angle, −180°."""
    deg = np.arange(-180.0, 180.1, 10.0)
    h = _history(deg, {"J": _cos(2.0, -1.0, 2.0, 3.0), "K": _cos(2.0, 1.0, 2.0, 0.0)}, _cos(0.0, 1.0, 1.0, 3.0),
                 full_turn=False)
    pk = peaks(h)
    j = pk["J"]
    assert j["force_N"] == pytest.approx(3.0, rel=1e-12) and j["crank_deg"] == pytest.approx(-87.0, abs=1e-5)
    assert j["equal_peaks_deg"] == pytest.approx([-87.0, 93.0], abs=1e-5)
    assert pk["K"]["force_N"] == pytest.approx(3.0, rel=1e-12) and pk["K"]["crank_deg"] == -180.0


def test_a_part_turn_refines_its_inner_peaks_and_keeps_its_ends():
    """Over 0..90°: 2 + cos(360/66·(θ − 12°)) peaks equally at 12° and 78° (found from the second
    and the second-last sample); 2 + cos(θ + 30°) falls and 2 + cos(θ − 120°) rises all the way, so
    they peak at the ends, 0° and 90°, with 2 + cos 30°, whatever they do beyond."""
    deg = np.arange(0.0, 90.1, 10.0)
    h = _history(deg, {"J": _cos(2.0, 1.0, 360.0 / 66.0, 12.0), "K": _cos(2.0, 1.0, 1.0, -30.0)},
                 _cos(2.0, 1.0, 1.0, 120.0), full_turn=False)
    pk = peaks(h)
    assert pk["J"]["force_N"] == pytest.approx(3.0, rel=1e-12) and pk["J"]["crank_deg"] == pytest.approx(12.0, abs=1e-5)
    assert pk["J"]["equal_peaks_deg"] == pytest.approx([12.0, 78.0], abs=1e-5)
    end = 2.0 + np.cos(np.radians(30.0))
    assert (pk["K"]["force_N"], pk["K"]["crank_deg"]) == (pytest.approx(end, rel=1e-12), 0.0)
    assert (pk["torque"]["peak"], pk["torque"]["value"], pk["torque"]["crank_deg"]) == (
        pytest.approx(end, rel=1e-12), pytest.approx(end, rel=1e-12), 90.0)


def test_unrefined_peaks_are_the_largest_samples():
    """Without refining, the peak is the largest sample, with its force components and signed
    torque: 2 + cos(θ − 40°) (and 1 N across) at 40°, −(1.5 + cos(θ − 200°)) at 200°."""
    h = _history(crank_angles(36), {"J": _cos(2.0, 1.0, 1.0, 40.0)}, lambda t: -_cos(1.5, 1.0, 1.0, 200.0)(t),
                 full_turn=True)
    h.joints["J"].force_N[:, 1] = 1.0
    pk = peaks(h, refine=False)
    assert (pk["J"]["crank_deg"], pk["J"]["fx_N"], pk["J"]["fy_N"]) == (40.0, 3.0, 1.0)
    assert pk["J"]["force_N"] == pytest.approx(np.hypot(3.0, 1.0), rel=1e-15)
    assert (pk["torque"]["crank_deg"], pk["torque"]["peak"], pk["torque"]["value"]) == (200.0, 2.5, -2.5)


def test_three_samples_and_no_evaluator_give_the_largest_sample():
    """Too few samples for a spline and no evaluator: the peaks are the largest samples."""
    h = _history(np.array([0.0, 120.0, 240.0]), {"J": _cos(2.0, 1.0, 1.0, 120.0)}, _cos(0.0, -1.0, 1.0, 0.0),
                 full_turn=False, evaluate=False)
    pk = peaks(h)
    assert (pk["J"]["force_N"], pk["J"]["crank_deg"], pk["J"]["fx_N"]) == (3.0, 120.0, 3.0)
    assert (pk["torque"]["peak"], pk["torque"]["value"], pk["torque"]["crank_deg"]) == (1.0, -1.0, 0.0)


def test_a_stated_toggle_range_is_where_every_peak_is():
    """A history whose toggle the linkage puts at 37.5..45° (its samples flag 40° only) reports
    every peak unbounded at 37.5°."""
    deg = crank_angles(36)
    h = _history(deg, {"J": _cos(2.0, 1.0, 1.0, 100.0)}, _cos(0.0, 1.0, 1.0, 30.0), full_turn=True,
                 meta={"singular": [[37.5, 45.0]]})
    h.singular_mask = deg == 40.0
    pk = peaks(h)
    assert pk["J"] == {"crank_deg": 37.5, "singular": True, "force_N": None, "fx_N": None, "fy_N": None}
    assert pk["torque"] == {"crank_deg": 37.5, "singular": True, "peak": None, "value": None}


def test_a_toggle_between_samples_is_reported_where_it_is_met():
    """A toggle at 100.2..100.6°, between samples, beside the force's peak at 100.4°: met while
    refining, every peak is unbounded at an angle of it."""
    flag = lambda t: (np.asarray(t) >= 100.2) & (np.asarray(t) <= 100.6)
    h = _history(crank_angles(36), {"J": _cos(2.0, 1.0, 1.0, 100.4)}, _cos(0.0, 1.0, 1.0, 30.0), full_turn=True,
                 flag=flag)
    pk = peaks(h)
    for p in pk.values():
        assert p["singular"] is True and 100.2 <= p["crank_deg"] <= 100.6


def test_an_imported_turn_from_minus_5_degrees_finds_its_peaks_on_the_spline():
    """A CSV turn sampled every 10° from −5° (a periodic spline between): 2 + cos(θ + 7°) peaks at
    353° with 3 N, found from the sample at −5°; cos θ peaks equally at 0° and 180° (the samples
    straddle both alike), its value +1 N·m at 0° or −1 N·m at 180°."""
    deg = crank_angles(36, -5.0)
    h = _history(deg, {"J": _cos(2.0, 1.0, 1.0, -7.0)}, _cos(0.0, 1.0, 1.0, 0.0), full_turn=True, evaluate=False)
    pk = peaks(h)
    assert pk["J"]["force_N"] == pytest.approx(3.0, abs=2e-5) and _wrapped(pk["J"]["crank_deg"], 353.0) < 0.01
    tq = pk["torque"]
    assert tq["peak"] == pytest.approx(1.0, abs=2e-5)
    assert min(_wrapped(tq["crank_deg"], x) for x in (0.0, 180.0)) < 1e-5
    assert tq["value"] == pytest.approx(np.cos(np.radians(tq["crank_deg"])), abs=2e-5) and len(tq["equal_peaks_deg"]) == 2
    assert sorted(_wrapped(x, 0.0) for x in tq["equal_peaks_deg"]) == pytest.approx([0.0, 180.0], abs=1e-5)


def test_angles_closer_than_the_tolerance_are_one():
    """_distinct merges sorted angles within tol of the last kept (round the turn if periodic)
    and keeps those farther apart; exactly tol apart is within."""
    assert _distinct([2e-5, 0.5, 179.99996, 180.0, 359.99999], True) == [2e-5, 0.5, 179.99996]
    assert _distinct([2e-5, 359.99999], True) == [2e-5]
    assert _distinct([2e-5, 359.99999], False) == [2e-5, 359.99999]
    assert _distinct([0.0, 0.5, 1.25], False, tol=0.5) == [0.0, 1.25]
    assert _distinct([0.25, 180.0, 359.75], True, tol=0.5) == [0.25, 180.0]


@pytest.mark.parametrize("samples", [8, 8.0, 1_000_000])
def test_options_accept_the_ends_of_the_samples_range(samples):
    assert DynamicsOptions(samples=samples).samples == samples


@pytest.mark.parametrize("samples", [7, 1_000_001, 100.5, None, float("inf"), float("nan"), "360"])
def test_options_refuse_samples_outside_the_range(samples):
    with pytest.raises(InputError, match=r"must be a whole number in \[8, 1000000\]"):
        DynamicsOptions(samples=samples)


@pytest.mark.parametrize("speed", [100.0, -100.0, 1e-9])
def test_options_accept_the_ends_of_the_speed_range(speed):
    assert DynamicsOptions(speed_hz=speed).speed_hz == speed


@pytest.mark.parametrize("speed", [0.0, float(np.nextafter(100.0, np.inf)), -float(np.nextafter(100.0, np.inf)),
                                   100.5, float("nan"), float("inf"), None, "1"])
def test_options_refuse_speeds_outside_the_range(speed):
    with pytest.raises(InputError, match=r"must be non-zero and within \[-100, 100\] Hz"):
        DynamicsOptions(speed_hz=speed)


def test_a_summary_without_warnings_states_none():
    """A history that states no warnings (an imported CSV's) summarises them as an empty list."""
    h = _history(crank_angles(36), {"J": _cos(2.0, 1.0, 1.0, 100.0)}, _cos(0.0, 1.0, 1.0, 30.0), full_turn=True)
    s = summary(h)
    assert s["warnings"] == [] and s["textbook"] is False and s["samples"] == 36
