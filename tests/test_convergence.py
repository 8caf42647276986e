"""Convergence study: Richardson extrapolation (exact on synthetic sequences), singular flag,
CLI refusals."""

import json
import math

import pytest

from rigfem.cli import main
from rigfem.convergence import richardson
from rigfem.errors import InputError


@pytest.mark.parametrize("h", [[1.6, 0.8, 0.4, 0.2], [2.4, 1.7, 1.2, 0.85, 0.6], [2.0, 1.3, 0.7]])
@pytest.mark.parametrize("p", [1.0, 1.5, 2.0])
def test_richardson_exact_on_known_order_and_limit(h, p):
    ex = richardson(h, [250.0 - 7.0 * x ** p for x in h])
    assert ex.converging and ex.order == pytest.approx(p, abs=1e-9)
    assert ex.limit == pytest.approx(250.0, abs=1e-9)
    assert ex.asymptotic == (len(h) >= 4)
    assert all(o == pytest.approx(p, abs=1e-9) for o in ex.orders)


@pytest.mark.parametrize("q", [[100 * x ** -0.45 for x in (1.6, 0.8, 0.4, 0.2)],  # re-entrant corner
                               [100.0, 110.0, 120.0, 130.0]])  # log-like growth, equal differences
def test_singular_sequence_is_flagged_not_converged(q):
    ex = richardson([1.6, 0.8, 0.4, 0.2], q)
    assert not ex.converging and ex.limit is None and ex.order is None
    assert "singular" in ex.note
    assert "NaN" not in json.dumps(ex.as_dict())


def test_oscillating_sequence_has_no_richardson_limit():
    ex = richardson([1.6, 0.8, 0.4], [100.0, 110.0, 105.0])
    assert ex.converging and ex.order is None and ex.limit == 105.0
    assert ex.gci == pytest.approx(5.0 / 105.0) and "oscillating" in ex.note


def test_richardson_refuses_bad_sequences():
    with pytest.raises(InputError, match="at least 3"):
        richardson([1.0, 0.5], [1.0, 2.0])
    with pytest.raises(InputError, match="decreasing"):
        richardson([0.5, 1.0, 2.0], [1.0, 2.0, 3.0])
    with pytest.raises(InputError):
        richardson([1.0, 0.5, 0.25], [1.0, math.nan, 2.0])


@pytest.mark.parametrize("argv, msg", [
    (["plate_A", "--levels", "2"], "--levels"),
    (["plate_A", "--levels", "4.5"], "--levels"),
    (["plate_A", "--mode", "static"], "--mode"),
    (["plate_A", "--ratio", "5"], "--ratio"),
    (["plate_A", "--max-gib", "nan"], "--max-gib"),
    (["no-such-scene"], "no-such-scene"),
])
def test_cli_bad_input_is_one_line_exit_2(argv, msg, capsys, tmp_path):
    assert main(["convergence", *argv, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rigfem: error:") and msg in err and err.count("\n") == 1
