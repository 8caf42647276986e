"""geometry/RIG.md §2 rules: each rule passes and fails where the table says."""

import numpy as np
import pytest

from rigfem.rig import (
    fourbar_rules,
    rules_for,
    slider_crank_rules,
    transmission_angle_range,
)


def _by_prefix(rules, prefix):
    (r,) = [r for r in rules if r.name.startswith(prefix)]
    return r


def test_reference_configuration():
    rules = fourbar_rules(540, 840, 780, 1020)
    ok = {r.name.split(" (")[0]: r.ok for r in rules}
    assert ok == {"loop can close": True, "crank turns fully": True,
                  "crank guide clears the rocker pivot": True, "transmission angle min": False,
                  "transmission angle max": False, "on the hole grid": True}
    # the study's final figures: mu 34.2160 / 148.6930 deg (outside 35..145, "does not comply")
    assert _by_prefix(rules, "transmission angle min").value == pytest.approx(34.2160, abs=1e-4)
    assert _by_prefix(rules, "transmission angle max").value == pytest.approx(148.6930, abs=1e-4)


@pytest.mark.parametrize("lengths,prefix,ok", [
    ((300, 600, 600, 1600), "loop can close", False),
    ((300, 600, 600, 1400), "loop can close", True),
    ((540, 840, 780, 1080), "crank turns fully", False),      # b2 + d == b3 + b4: change point
    ((540, 840, 780, 1020), "crank turns fully", True),
    ((300, 720, 660, 600), "crank guide clears", False),
    ((300, 720, 660, 660), "crank guide clears", True),
    ((540, 840, 780, 1021), "on the hole grid", False),
    ((540, 840, 780, 1020), "on the hole grid", True),
    ((240, 840, 780, 900), "transmission angle min", True),
    ((240, 840, 780, 900), "transmission angle max", True),
])
def test_each_fourbar_rule(lengths, prefix, ok):
    assert _by_prefix(fourbar_rules(*lengths), prefix).ok is ok


def test_transmission_angle_limits_are_strict():
    lo, hi = transmission_angle_range(240, 840, 780, 900)
    assert 35 < lo < hi < 145
    b3, b4, d = 840.0, 780.0, 900.0
    # choose b2 so that mu_min is exactly 35 deg: (d - b2)^2 = b3^2 + b4^2 - 2 b3 b4 cos 35
    b2 = d - np.sqrt(b3**2 + b4**2 - 2 * b3 * b4 * np.cos(np.radians(35.0)))
    assert _by_prefix(fourbar_rules(b2, b3, b4, d), "transmission angle min").ok is False
    assert _by_prefix(fourbar_rules(b2 - 1e-6, b3, b4, d), "transmission angle min").ok is True


def test_slider_crank_rules():
    assert _by_prefix(slider_crank_rules(300, 600), "rod and crank").ok
    assert not _by_prefix(slider_crank_rules(600, 600), "rod and crank").ok
    assert not _by_prefix(slider_crank_rules(300, 420, 180), "crank turns fully").ok
    assert not _by_prefix(slider_crank_rules(300, 610), "on the hole grid").ok
    assert rules_for({"type": "quick-return"}) == []
