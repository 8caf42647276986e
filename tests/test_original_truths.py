"""The 2013 model (rigfem.dynamics.original) with a sample exactly at a change point, against truths
written without rigfem.

300/600/400/500 mm folds flat with the crank at 0° (b2 + b3 = b4 + d, d − b2 = b3 − b4): A, O4 and B
lie on the ground line, the coupler and the rocker are collinear and the program's 9 equations have
no solution there (no finite reaction: a toggle).  Sampled every 30° from 0° at 1.3 Hz:

* the change point's sample is flagged and its numbers are given as 0 (none is non-finite);
* every other sample is the 2013 program written from geometry/RIG.md §3 (tests/newton_euler.py
  ``study_program``, open assembly) and the model's own reactions for the samples without the change
  point: one singular sample does not spoil the others;
* the whole linkage's force balance by hand: the ground's forces R12 + R14 equal the bodies' Σ m a as
  the 2013 program places its masses (each guide rail at its bar's combined centre of mass, the
  point masses at A and B, no gravity).
"""

import numpy as np
import pytest
from newton_euler import CARRIAGE, COUPLING, PLATE, RAILS_MM, STUDY_RAIL_KG_M, fourbar_motion, study_program

from rigfem.dynamics.cycle import cycle_history
from rigfem.dynamics.original import program_kinematics, program_reactions
from rigfem.linkage import four_bar
from rigfem.linkage.state import linkage_state

CHANGE_POINT = (300.0, 600.0, 400.0, 500.0)
DEG = np.arange(0.0, 360.0, 30.0)  # the change point (0°) is the first sample
HZ = 1.3


def _study(t: float) -> tuple[np.ndarray, float, float]:
    """study_program at crank ``t``: the four pin forces as an (4, 2) array (O2, A, B, O4), the motor
    torque and the largest force (the scale of the tolerance)."""
    F, T, _ = study_program(*CHANGE_POINT, t, HZ)
    forces = np.array([[F[n].real, F[n].imag] for n in ("O2", "A", "B", "O4")])
    return forces, T, float(np.abs(forces).max())


def test_the_2013_model_flags_a_sample_at_a_change_point_and_solves_every_other_one_alone():
    """simulate's 2013 model (cycle_history) with a sample exactly at the change point: that sample is
    a toggle with its forces and torque 0; the others are the study program's and equal the model's
    on the samples without the change point to 1e-12 (the per-sample fallback solves each as the
    batch would)."""
    lk = four_bar(*CHANGE_POINT)
    h = cycle_history(lk, linkage_state(lk, DEG, HZ), DEG, HZ, "original")
    assert np.array_equal(h.singular_mask, DEG == 0.0) and h.meta["singular"][0][0] == 0.0
    assert all(np.isfinite(j.force_N).all() for j in h.joints.values()) and np.isfinite(h.torque_Nm).all()
    assert all(np.array_equal(j.force_N[0], [0.0, 0.0]) for j in h.joints.values()) and h.torque_Nm[0] == 0.0
    alone = cycle_history(lk, linkage_state(lk, DEG[1:], HZ), DEG[1:], HZ, "original")
    assert alone.singular_mask is None
    for n in ("O2", "A", "B", "O4"):
        assert np.allclose(h.joints[n].force_N[1:], alone.joints[n].force_N, rtol=1e-12, atol=0), n
    assert np.allclose(h.torque_Nm[1:], alone.torque_Nm, rtol=1e-12, atol=0)
    for i, t in enumerate(DEG[1:], 1):
        forces, torque, scale = _study(t)
        got = np.array([h.joints[n].force_N[i] for n in ("O2", "A", "B", "O4")])
        assert np.allclose(got, forces, rtol=0, atol=1e-12 * scale), t
        assert h.torque_Nm[i] == pytest.approx(torque, abs=1e-12 * scale), t


def test_program_reactions_leaves_the_change_point_without_a_number_and_balances_the_rest():
    """program_reactions on the same motion: the change point's row is NaN throughout (no finite
    reaction), every other row is the study program's and R12 + R14 = Σ m a of the bodies (by hand,
    at 90°)."""
    lk = four_bar(*CHANGE_POINT)
    b2, b3, b4, _ = (x / 1000 for x in CHANGE_POINT)
    r = program_reactions(program_kinematics(linkage_state(lk, DEG, HZ), b2, b3, 2 * np.pi * HZ),
                          *CHANGE_POINT[:3], HZ)
    rows = np.concatenate([r["R12"], r["R23"], r["R34"], r["R14"], r["M2"][:, None]], axis=1)
    assert rows.shape == (DEG.size, 9) and rows.dtype == float
    assert np.isnan(rows[0]).all() and np.isfinite(rows[1:]).all()
    for i, t in enumerate(DEG[1:], 1):
        forces, torque, scale = _study(t)
        assert np.allclose(rows[i, :8].reshape(4, 2), forces, rtol=0, atol=1e-12 * scale), t
        assert rows[i, 8] == pytest.approx(torque, abs=1e-12 * scale), t
    # Σ m a at 90°: rails of 2.7 kg/m at their bars' combined centres of mass, plate + carriage at A
    # (crank) and B (coupler), a coupling at A (coupler) and B (rocker)
    k = fourbar_motion(*CHANGE_POINT, 90.0, HZ)
    (e2, e3, e4), (w2, w3, w4), (_, a3, a4) = k["e"], k["w"], k["al"]
    m2, m3, m4 = (STUDY_RAIL_KG_M * L / 1000 for L in RAILS_MM)
    mp = PLATE + CARRIAGE
    x2, x3, x4 = ((L / 2000 * m + b * mq) / (m + mq) for L, m, b, mq in
                  ((RAILS_MM[0], m2, b2, mp), (RAILS_MM[1], m3, b3, mp), (RAILS_MM[2], m4, b4, COUPLING)))
    aA = -(w2**2) * b2 * e2
    aB = aA + b3 * (1j * a3 - w3**2) * e3
    total = (m2 * -(w2**2) * x2 * e2 + mp * aA + m3 * (aA + x3 * (1j * a3 - w3**2) * e3) + COUPLING * aA
             + mp * aB + m4 * x4 * (1j * a4 - w4**2) * e4 + COUPLING * aB)
    i = int(np.flatnonzero(DEG == 90.0)[0])
    assert np.allclose(r["R12"][i] + r["R14"][i], [total.real, total.imag], rtol=0, atol=1e-12 * abs(total))
