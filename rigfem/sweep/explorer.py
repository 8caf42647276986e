"""The design-space explorer: one offline page where a student picks a rig configuration.

Built from the sweep's tables (results/sweep/): for the picked lengths it shows, in the one
vocabulary of :mod:`rigfem.rig.rules`, whether the linkage assembles, meets the rig rules (each with
its numbers, geometry/RIG.md §2) and passes the stress criterion (the worst part with its
utilisation and error band), the transmission-angle range, the linkage turning (closed-form
position analysis in the page) and utilisation maps sliced through the picked point.
"""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

from rigfem.files import whole_file
from rigfem.report.pages import json_script, render_page
from rigfem.rig.rules import ASSEMBLES, MEETS_RULES, STRESS, fourbar_rules, slider_crank_rules
from rigfem.sweep.configs import JOINTS, LENGTHS

__all__ = ["explorer_data", "write_explorer"]


def _num(v, digits: int = 4) -> float | None:
    """A finite number rounded to ``digits`` significant figures, or None (no number: JSON null)."""
    try:
        v = float(v)
    except (TypeError, ValueError):
        return None
    if not math.isfinite(v):
        return None
    v = float(f"{v:.{digits}g}")
    return int(v) if v.is_integer() else v


def _column(values: list) -> list | float | int | None:
    """A column, or its one value where every row has the same (a rule's fixed limit)."""
    return values[0] if values and all(v == values[0] for v in values) else values


def _codes(col: pd.Series) -> tuple[list[str], list[int]]:
    """A text column as a list of distinct values and one index per row (-1: empty)."""
    names = sorted(str(v) for v in col.dropna().unique())
    index = {n: i for i, n in enumerate(names)}
    return names, [-1 if pd.isna(v) else index[str(v)] for v in col]


def explorer_data(kind: str, table: pd.DataFrame) -> dict:
    """The columns of one linkage type's sweep table that the explorer shows, compact."""
    lengths = list(LENGTHS[kind])
    rules_of = fourbar_rules if kind == "four-bar" else slider_crank_rules
    rules = [rules_of(**{k: float(r[k]) for k in lengths}) for r in table[lengths].to_dict("records")]
    data = {"lengths": lengths, "grid": {k: sorted(float(v) for v in table[k].unique()) for k in lengths},
            "keys": [[_num(r[k]) for k in lengths] for r in table[lengths].to_dict("records")],
            "rules": [{"name": rule.name, "relation": rule.relation, "unit": rule.unit,
                       "value": _column([_num(rs[i].value) for rs in rules]),
                       "limit": _column([_num(rs[i].limit) for rs in rules]),
                       "ok": "".join(str(int(rs[i].ok)) for rs in rules)} for i, rule in enumerate(rules[0])] if rules else [],
            "joints": list(JOINTS[kind])}
    for col in ("status", "note"):
        data[f"{col}_names"], data[col] = _codes(table[col])
    done = (table["status"] == "ok").to_numpy()
    data["computed"] = [int(i) for i in done.nonzero()[0]]  # the result columns below hold these rows only
    for col in ("limiting_part", "verdict"):
        data[f"{col}_names"], data[col] = _codes(table[col][done])
    for col in ["mu_min_deg", "mu_max_deg", "max_util_pct", "error_pct", "peak_torque_Nm"] + \
               [f"peak_{j}_N" for j in JOINTS[kind]]:
        if col in table:
            data[col] = [_num(v) for v in table[col][done]]
    data["rules_ok"] = "".join(str(int(bool(v))) for v in table["rules_ok"])
    return data


def write_explorer(out: Path, tables: dict[str, pd.DataFrame], name: str = "explorer.html") -> Path:
    """Write the explorer page for the given linkage types' tables into ``out``."""
    data = {kind: explorer_data(kind, t) for kind, t in tables.items()}
    path = Path(out) / name
    words = json_script({"assembles": ASSEMBLES, "rules": MEETS_RULES, "stress": STRESS})
    with whole_file(path) as tmp:
        tmp.write_text(render_page("explorer.html.j2", kinds=list(data), data=json_script(data), words=words),
                       encoding="utf-8")
    return path
