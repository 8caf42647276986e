"""Two check reports side by side (``rigfem compare``): per part and mode the peak, utilisation
and band of each, the change, and which verdicts changed; as a dict, Markdown and HTML.

A verdict got *worse* when it moved down the order pass → undecided / not loaded → fail (the
overall verdict too); a part case checked in one report only is listed, never judged.
"""

from __future__ import annotations

from rigfem.report.document import md_text, verdict_line
from rigfem.report.figures import part_label
from rigfem.report.pages import markdown_html, render_page

__all__ = ["RANK", "compare", "render_compare_markdown", "render_compare_html"]

#: how bad a verdict is: a change to a higher rank is worse
RANK = {"pass": 0, "undecided": 1, "not loaded": 1, "fail": 2}


def _change(a: str | None, b: str | None) -> str:
    if a is None or b is None:
        return f"only in {'B' if a is None else 'A'}"
    return "same" if a == b else "worse" if RANK[b] > RANK[a] else "better" if RANK[b] < RANK[a] else "changed"


def _side(p: dict | None) -> dict | None:
    if p is None:
        return None
    return {k: p.get(k) for k in ("verdict", "peak_mpa", "utilisation_pct", "error_pct", "crank_deg")}


def compare(a: dict, b: dict, names: tuple[str, str] = ("A", "B")) -> dict:
    """The comparison of reports ``a`` and ``b`` (report.json dicts; ``names``: how they are called):
    every part case of either, in ``a``'s order then ``b``'s new ones, and the overall verdicts."""
    pa = {(p["name"], p["mode"]): p for p in a["parts"]}
    pb = {(p["name"], p["mode"]): p for p in b["parts"]}
    rows = []
    for key in [*pa, *(k for k in pb if k not in pa)]:
        x, y = pa.get(key), pb.get(key)
        row = {"name": key[0], "part": (x or y)["part"], "mode": key[1], "a": _side(x), "b": _side(y),
               "change": _change(x and x["verdict"], y and y["verdict"]), "peak_change_mpa": None,
               "peak_change_pct": None, "utilisation_change_pct": None}
        if x and y and x.get("peak_mpa") is not None and y.get("peak_mpa") is not None:
            row["peak_change_mpa"] = y["peak_mpa"] - x["peak_mpa"]
            row["peak_change_pct"] = 100 * row["peak_change_mpa"] / x["peak_mpa"] if x["peak_mpa"] else None
            row["utilisation_change_pct"] = y["utilisation_pct"] - x["utilisation_pct"]
        rows.append(row)
    overall = _change(a["verdict"], b["verdict"])
    worse = [f"{r['name']} {r['mode']}" for r in rows if r["change"] == "worse"] + (["overall"] if overall == "worse" else [])
    return {"names": list(names), "scenes": [a["scene"], b["scene"]],
            "lengths_mm": [a["configuration"]["lengths_mm"], b["configuration"]["lengths_mm"]],
            "verdicts": [verdict_line(a), verdict_line(b)], "overall_change": overall,
            "limits_mpa": [a["limit_mpa"], b["limit_mpa"]], "rows": rows, "worse": worse}


def _num(x, nd: int = 1, sign: bool = False) -> str:
    return "–" if x is None else f"{x:+.{nd}f}" if sign else f"{x:.{nd}f}"


def _cell(side: dict | None) -> tuple[str, str, str]:
    if side is None:
        return "not checked", "–", "–"
    if side["peak_mpa"] is None:
        return side["verdict"].upper(), "–", "–"
    return (side["verdict"].upper(), f"{side['peak_mpa']:.1f}",
            f"{side['utilisation_pct']:.1f} ± {side['utilisation_pct'] * side['error_pct'] / 100:.1f}")


def render_compare_markdown(c: dict) -> str:
    """The comparison as Markdown: what was compared, the overall verdicts, one row per part case."""
    na, nb = (md_text(n) for n in c["names"])
    lengths = [", ".join(f"{k} = {v:g}" for k, v in ln.items()) for ln in c["lengths_mm"]]
    lines = [f"# rigfem compare: {na} vs {nb}", "",
             f"- A: {na}, scene {md_text(c['scenes'][0])} ({lengths[0]} mm), verdict **{c['verdicts'][0]}**",
             f"- B: {nb}, scene {md_text(c['scenes'][1])} ({lengths[1]} mm), verdict **{c['verdicts'][1]}**",
             f"- overall verdict: **{c['overall_change']}**"
             + (f"; allowable {c['limits_mpa'][0]:.0f} MPa in A, {c['limits_mpa'][1]:.0f} MPa in B"
                if c["limits_mpa"][0] != c["limits_mpa"][1] else f"; allowable {c['limits_mpa'][0]:.0f} MPa"),
             "",
             "**Verdicts that got worse: " + (", ".join(c["worse"]) if c["worse"] else "none") + "**", "",
             "| part | mode | verdict A | verdict B | change | peak σvm A (MPa) | peak σvm B (MPa) | Δ peak (MPa) | "
             "Δ peak (%) | utilisation A (% ± band) | utilisation B (% ± band) | Δ utilisation (points of %) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in c["rows"]:
        va, pa, ua = _cell(r["a"])
        vb, pb, ub = _cell(r["b"])
        change = f"**{r['change']}**" if r["change"] in ("worse", "better") else r["change"]
        lines.append(f"| {md_text(part_label(r['name'], r['part']))} | {r['mode']} | {va} | {vb} | {change} | {pa} | "
                     f"{pb} | {_num(r['peak_change_mpa'], 1, True)} | {_num(r['peak_change_pct'], 1, True)} | "
                     f"{ua} | {ub} | {_num(r['utilisation_change_pct'], 1, True)} |")
    lines += ["", "A verdict is worse when it moves down pass → undecided (or not loaded) → fail. The band is "
              "the peak's error estimate (an estimate, not a bound): a change within both bands is not a "
              "measured change.", ""]
    return "\n".join(lines)


def render_compare_html(c: dict) -> str:
    """The comparison as one HTML page (the Markdown's content)."""
    return render_page("compare.html.j2", c=c, body=markdown_html(render_compare_markdown(c)))
