"""Issue 38, a PASS from almost no data: imported reactions whose rows are mostly blank and marked
singular read PASS on the one real row (a toggle's rows were zeroed and the check that the
samples resolve the peaks skipped).  Now: more than MAX_SINGULAR_SHARE of the rows marked
singular is refused with one line; fewer make the history a toggle's (no finite peak, every part
fails, as rigfem's own dynamics of a toggle); the peak-resolution check runs on the other rows;
a column given twice (or two columns for one role) is refused, not taken silently."""

from __future__ import annotations

import csv
import io

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rigfem.dynamics.history import peaks
from rigfem.errors import InputError
from rigfem.io.reactions_csv import MAX_SINGULAR_SHARE, read_csv, write_csv

SETTINGS = settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
FAST = {"parts": ["plate_A"], "modes": ["original"], "fidelity": "draft", "frames": 0}


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> tuple[list[str], list[str], list[list[str]]]:
    """final-cm's own 360-row CSV: (comment lines, header, rows)."""
    from rigfem.cache import NO_CACHE
    from rigfem.job import Request, read_job
    from rigfem.dynamics.cycle import simulate

    path = tmp_path_factory.mktemp("ref") / "final-cm.csv"
    write_csv(simulate(read_job(Request("final-cm"), NO_CACHE).linkage, samples=360), path)
    lines = path.read_text().splitlines()
    comments = [ln for ln in lines if ln.startswith("#")]
    table = list(csv.reader(ln for ln in lines if not ln.startswith("#")))
    return comments, table[0], table[1:]


def _write(path, comments, head, rows) -> None:
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerows([head, *rows])
    path.write_text("\n".join(comments) + "\n" + out.getvalue())


def _blank(row: list[str]) -> list[str]:
    """The row as a toggle's: its angle, no forces, marked singular."""
    return [row[0], *[""] * (len(row) - 2), "1"]


@SETTINGS
@given(data=st.data())
def test_rows_marked_singular_are_refused_past_a_small_share_else_no_peak(tmp_path_factory, reference, data):
    comments, head, rows = reference
    k = data.draw(st.one_of(st.integers(1, 360 - 1), st.sampled_from([1, 18, 19, 359])), label="rows blanked")
    chosen = set(data.draw(st.permutations(range(360)), label="order")[:k])
    path = tmp_path_factory.mktemp("csv") / "r.csv"
    _write(path, comments, head, [_blank(r) if i in chosen else r for i, r in enumerate(rows)])
    if k / 360 > MAX_SINGULAR_SHARE:
        with pytest.raises(InputError, match=rf"{k} of 360 rows are marked singular") as e:
            read_csv(path)
        assert "\n" not in str(e.value)
        return
    h = read_csv(path)
    assert h.meta["singular"] and h.singular_mask.sum() == k
    assert all(p.get("force_N", p.get("peak")) is None and p["singular"] for p in peaks(h).values())


@pytest.mark.parametrize("blank, verdict", [(range(100, 110), "fail"), (range(1, 360), None)])
def test_a_check_on_mostly_blank_reactions_never_passes(tmp_path, reference, blank, verdict):
    from rigfem.pipeline import Output, Request, run_check
    from rigfem.scene import builtin_scenes

    comments, head, rows = reference
    (tmp_path / "final-cm.toml").write_bytes(builtin_scenes()["final-cm"].read_bytes())
    _write(tmp_path / "r.csv", comments, head, [_blank(r) if i in blank else r for i, r in enumerate(rows)])
    overrides = {**FAST, "reactions_csv": str(tmp_path / "r.csv")}
    if verdict is None:  # 359 of 360 rows: refused, one line
        with pytest.raises(InputError, match="359 of 360 rows are marked singular"):
            run_check(Request(tmp_path / "final-cm.toml", overrides), Output(tmp_path / "o"))
        assert not (tmp_path / "o").exists()
        return
    r = run_check(Request(tmp_path / "final-cm.toml", overrides), Output(tmp_path / "o", pictures=False))
    assert r["verdict"] == "fail" and r["singular"] and all(p["verdict"] != "pass" for p in r["parts"])


@SETTINGS
@given(data=st.data())
def test_a_column_given_twice_is_refused(tmp_path_factory, reference, data):
    comments, head, rows = reference
    i = data.draw(st.integers(0, len(head) - 1), label="column")
    name = data.draw(st.sampled_from([head[i], head[i].upper(), head[i].lower()]), label="spelled")
    path = tmp_path_factory.mktemp("csv") / "r.csv"
    _write(path, comments, [*head, name], [[*r, r[i]] for r in rows])
    with pytest.raises(InputError, match=rf"column {head[i]} appears 2 times") as e:
        read_csv(path)
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("extra, needle", [("M2", "2 driver columns (torque_Nm, M2)"),
                                           ("theta", "2 crank-angle columns (crank_deg, theta)")])
def test_two_columns_for_one_role_are_refused(tmp_path, reference, extra, needle):
    comments, head, rows = reference
    col = head.index("torque_Nm" if extra == "M2" else "crank_deg")
    _write(tmp_path / "r.csv", comments, [*head, extra], [[*r, r[col]] for r in rows])
    with pytest.raises(InputError, match=needle.replace("(", r"\(").replace(")", r"\)")):
        read_csv(tmp_path / "r.csv")


def test_a_joint_with_two_pairs_of_columns_is_refused(tmp_path, reference):
    comments, head, rows = reference
    fx, fy = head.index("A_fx_N"), head.index("A_fy_N")
    _write(tmp_path / "r.csv", comments, [*head, "A_fx", "A_fy"], [[*r, r[fx], r[fy]] for r in rows])
    with pytest.raises(InputError, match="joint A has two pairs of force columns"):
        read_csv(tmp_path / "r.csv")


def test_singular_rows_do_not_switch_off_the_peak_resolution_check(tmp_path):
    """36 samples of a sharp peak are refused as too coarse, also with one row marked singular
    far from the peak (that row used to skip the check for the whole history)."""
    deg = np.arange(0.0, 360.0, 10.0)
    f = 200.0 + 2000.0 * np.exp(-(((deg - 93.0) / 9.0) ** 2))
    rows = [[f"{a:g}", f"{x:.6f}", "0", f"{x:.6f}", "1.0", "0"] for a, x in zip(deg, f)]
    rows[30] = _blank(rows[30])
    _write(tmp_path / "r.csv", [], ["crank_deg", "P_fx_N", "P_fy_N", "P_F_N", "torque_Nm", "singular"], rows)
    with pytest.raises(InputError, match="sampled too coarsely"):
        read_csv(tmp_path / "r.csv")
