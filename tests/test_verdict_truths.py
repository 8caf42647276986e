"""The verdict's rules against the numbers the README and geometry/RIG.md state, written here
(not read from rigfem): σu/2 = 375 MPa for the rig steel, the undecided band, a free body's 5 %
imbalance tolerance, the Goodman line with Se' = Sut/2 (issue 39: the mutation tests'
survivors in rigfem/verdict/)."""

import numpy as np
import pytest

from rigfem.errors import InputError
from rigfem.verdict import goodman, half_ultimate, marin_endurance, overall
from rigfem.verdict.criterion import allowable_stress


def test_a_free_body_out_of_balance_by_more_than_five_percent_is_undecided():
    """README: above 5 % of the applied load (force) or of load × lever (moment) the part is undecided."""
    assert half_ultimate(30.0, 750.0, imbalance=(0.049, 0.049)).verdict == "pass"
    for imb in ((0.051, 0.0), (0.0, 0.051), (0.3, 0.2)):
        v = half_ultimate(30.0, 750.0, imbalance=imb)
        assert v.verdict == "undecided" and "tolerance 5 %" in v.reason, imb
    assert half_ultimate(400.0, 750.0, imbalance=(0.3, 0.0)).verdict == "fail"  # failing stays failing
