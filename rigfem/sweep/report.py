"""What a sweep table says: utilisation maps (PNG) and the worst configurations (Markdown).

The worst list is set beside the 2013 study's hand-found worst cases (geometry/RIG.md §3: the largest
reactions for the smallest mechanisms and for transmission angles near the limits), with the
rank correlations that test both statements on every configuration the sweep computed.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
import pandas as pd

from rigfem.files import whole_file
from rigfem.report.scale import NO_DATA_COLOUR, UTILISATION_SCALE_PCT, colormap
from rigfem.rig.rules import fourbar_rules, slider_crank_rules
from rigfem.sweep.run import JOINTS, LENGTHS, SweepParams

#: rows in each worst-configuration list
WORST = 15
#: the design-space explorer's page, written beside the sweep pages
EXPLORER = "explorer.html"
#: the 2013 study's final design (geometry/RIG.md §3), marked on the maps
FINAL_DESIGN = {"b2": 480.0, "b3": 840.0, "b4": 780.0, "d": 1020.0}


def _ok(table: pd.DataFrame) -> pd.DataFrame:
    """Computed rows, with the utilisation of the cases whose load depends on the configuration
    (``config_util_pct``, ``config_limiting``): a case with the same utilisation everywhere (the
    study's fixed 1000 N on the I-profile post) would otherwise tie every configuration."""
    ok = table[table["status"] == "ok"].copy()
    cols = [c for c in ok if c.endswith("_util_pct") and c != "max_util_pct"]
    if ok.empty or not cols:
        return ok
    span = ok[cols].max() - ok[cols].min()
    varying = [c for c in cols if len(ok) == 1 or span[c] > 1e-9 * max(1.0, ok[c].abs().max())]
    ok.attrs["fixed"] = {c[:-len("_util_pct")]: float(ok[c].iloc[0]) for c in cols if c not in varying}
    ok["config_util_pct"] = ok[varying].max(axis=1)
    ok["config_limiting"] = ok[varying].idxmax(axis=1).str.replace("_util_pct", "")
    return ok


def map_cells(table: pd.DataFrame, x: str, y: str, at: dict[str, float]) -> pd.DataFrame:
    """One map's cells: the computed configurations with ``at``'s lengths (the slice through it),
    indexed by (``y``, ``x``), each one real configuration with its own utilisation, verdict and rules."""
    ok = _ok(table)
    for k, v in at.items():
        ok = ok[ok[k] == v]
    return ok.set_index([y, x])[["config_util_pct", "verdict", "rules_ok"]]


def _panel(ax: "matplotlib.axes.Axes", cells: pd.DataFrame, xs: list, ys: list, cmap: "matplotlib.colors.Colormap",
           plt: "module") -> "matplotlib.image.AxesImage":
    """Draw one slice: colour by utilisation, hatch what does not meet the rig rules, outline what
    does not pass the stress criterion, a red line at 100 %; returns the image."""
    def grid(col: str) -> np.ndarray:
        return cells[col].unstack().reindex(index=ys, columns=xs).to_numpy() if len(cells) else \
            np.full((len(ys), len(xs)), np.nan)

    util = np.asarray(grid("config_util_pct"), dtype=float)
    vmin, vmax = UTILISATION_SCALE_PCT  # the report's one scale: yellow is 100 %, magenta above, everywhere
    im = ax.imshow(np.ma.masked_invalid(util), origin="lower", aspect="auto", vmin=vmin, vmax=vmax, cmap=cmap,
                   extent=(xs[0] - 30, xs[-1] + 30, ys[0] - 30, ys[-1] + 30))
    if np.nan_to_num(util, nan=0.0).max() >= 100.0:
        ax.contour(xs, ys, np.nan_to_num(util, nan=0.0), levels=[100.0], colors="r")
    rules = grid("rules_ok")
    verdict = grid("verdict")
    for (i, j) in zip(*np.nonzero(rules == False)):  # noqa: E712 (an object array: NaN where nothing computed)
        ax.add_patch(plt.Rectangle((xs[j] - 30, ys[i] - 30), 60, 60, fill=False, hatch="///", edgecolor="white", lw=0))
    for (i, j) in zip(*np.nonzero((verdict == "fail") | (verdict == "undecided"))):
        ax.add_patch(plt.Rectangle((xs[j] - 30, ys[i] - 30), 60, 60, fill=False, edgecolor="red", lw=1.2))
    ax.set_facecolor(NO_DATA_COLOUR)
    return im


#: what a map's cell is and what its marks mean, for every map's legend
LEGEND = ("each cell is one configuration; colour: its peak utilisation (% of σu/2) over the cases whose load "
          "depends on the configuration; grey: does not assemble (or passes a toggle: no number); "
          "hatched: does not meet the rig rules; red outline: fails the stress criterion or undecided")


def write_maps(table: pd.DataFrame, p: SweepParams, out: Path) -> list[str]:
    """PNG maps of the utilisation, slices through the study's final design; returns the file names."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = _ok(table)
    if ok.empty or "config_util_pct" not in ok:
        return []
    cmap = colormap()
    fixed = ", ".join(f"{_case(k)} {v:.1f} %" for k, v in ok.attrs.get("fixed", {}).items())
    note = f" (not shown, the same everywhere: {fixed})" if fixed else ""
    final = "/".join(f"{FINAL_DESIGN[k]:g}" for k in LENGTHS["four-bar"])
    files = []
    if p.linkage_type == "four-bar":
        for (x, y, hidden), name in ((("d", "b3", "b4"), "d_b3"), (("b4", "b3", "d"), "b4_b3")):
            b2s = sorted(table["b2"].unique())
            at = FINAL_DESIGN[hidden]
            cols = 3
            fig, axes = plt.subplots(int(np.ceil(len(b2s) / cols)), cols, figsize=(13, 3.6 * np.ceil(len(b2s) / cols)),
                                     squeeze=False, sharex=True, sharey=True)
            xs, ys = sorted(table[x].unique()), sorted(table[y].unique())
            im = None
            for ax, b2 in zip(axes.flat, b2s):
                im = _panel(ax, map_cells(table, x, y, {"b2": b2, hidden: at}), xs, ys, cmap, plt)
                if b2 == FINAL_DESIGN["b2"]:
                    ax.plot(FINAL_DESIGN[x], FINAL_DESIGN[y], marker="*", ms=14, color="white", mec="k")
                ax.set_title(f"b2 = {b2:g} mm, at {hidden} = {at:g} mm", fontsize="small")
            for ax in axes.flat[len(b2s):]:
                ax.axis("off")
            for ax in axes[-1]:
                ax.set_xlabel(f"{x} (mm)")
            for ax in axes[:, 0]:
                ax.set_ylabel(f"{y} (mm)")
            fig.colorbar(im, ax=axes, shrink=0.6, extend="max",
                         label="peak utilisation (% of σu/2); magenta: above 100 %")
            fig.suptitle(f"four-bar at {hidden} = {at:g} mm (the final design's): peak part utilisation vs σu/2 "
                         f"({p.speed_hz:g} Hz, {p.model}, {p.fidelity}){note}\n"
                         + textwrap.fill(f"{LEGEND}; ★ the study's final design {final} mm, on its own cell", 170),
                         fontsize="small")
            f = f"map_four-bar_{name}.png"
            with whole_file(out / f) as tmp:
                fig.savefig(tmp, dpi=90)
            plt.close(fig)
            files.append(f)
    else:
        xs, ys = sorted(table["b2"].unique()), sorted(table["b3"].unique())
        at = {k: float(table[k].iloc[0]) for k in LENGTHS[p.linkage_type] if k not in ("b2", "b3")}
        fig, ax = plt.subplots(figsize=(7, 6.2))
        im = _panel(ax, map_cells(table, "b2", "b3", at), xs, ys, cmap, plt)
        ax.set_xlabel("b2 (mm)"), ax.set_ylabel("b3 (mm)")
        fig.colorbar(im, extend="max", label="peak utilisation (% of σu/2); magenta: above 100 %")
        where = ", ".join(f"{k} = {v:g} mm" for k, v in at.items())
        ax.set_title(f"slider-crank at {where}: peak part utilisation, {p.speed_hz:g} Hz{note}\n"
                     + textwrap.fill(LEGEND, 80), fontsize="x-small")
        f = "map_slider-crank_b2_b3.png"
        with whole_file(out / f) as tmp:
            fig.savefig(tmp, dpi=90, bbox_inches="tight")
        plt.close(fig)
        files.append(f)
    return files


def _spearman(a: pd.Series, b: pd.Series) -> str:
    r = a.rank().corr(b.rank())
    return "n/a" if not np.isfinite(r) else f"{r:+.2f}"


#: the table columns the lists show, with readable headers and units
HEADERS = {"b2": "b2 (mm)", "b3": "b3 (mm)", "b4": "b4 (mm)", "d": "d (mm)", "offset": "offset (mm)",
           "mu_min_deg": "μ min (deg)", "mu_max_deg": "μ max (deg)", "broken_rules": "rig rules broken",
           "max_reaction_N": "largest peak reaction (N)", "peak_torque_Nm": "peak driver torque (N·m)",
           "config_limiting": "limiting case (configuration-dependent)",
           "config_util_pct": "its utilisation (% of σu/2)", "limiting_part": "limiting part (mode), every case",
           "max_util_pct": "peak utilisation, every case (% of σu/2)", "verdict": "stress criterion"}


def broken_rules_text(kind: str, lengths: dict[str, float]) -> str:
    """The rig rules a configuration breaks, each with its value and limit ("none" when it meets them)."""
    rules = (fourbar_rules if kind == "four-bar" else slider_crank_rules)(**lengths)
    broken = [f"{r.name.split(' (')[0]}: {r.value:.4g} {r.unit}, must be {r.relation} {r.limit:.4g} {r.unit}"
              for r in rules if not r.ok]
    return "; ".join(broken) or "none"


def _case(column: str) -> str:
    """A part case as the pages name it: ``crank_rail_original`` -> ``crank_rail (original)``."""
    return column.replace("_original", " (original)").replace("_cycle", " (cycle)")


def _fmt(df: pd.DataFrame, p: SweepParams) -> str:
    lengths = list(LENGTHS[p.linkage_type])
    cols = lengths + (["mu_min_deg", "mu_max_deg"] if p.linkage_type == "four-bar" else [])
    cols += ["broken_rules", "max_reaction_N", "peak_torque_Nm", "config_limiting", "config_util_pct",
             "limiting_part", "max_util_pct", "verdict"]
    df = df.assign(broken_rules=[broken_rules_text(p.linkage_type, {k: float(r[k]) for k in lengths})
                                 for _, r in df.iterrows()])
    head = "| " + " | ".join(HEADERS[c] for c in cols) + " |\n|" + "---|" * len(cols) + "\n"
    lines = []
    for _, r in df.iterrows():
        cells = []
        for c in cols:
            v = r[c]
            cells.append("–" if pd.isna(v) else f"{v:.1f}" if isinstance(v, float) else _case(str(v)))
        lines.append("| " + " | ".join(cells) + " |")
    return head + "\n".join(lines) + "\n"


def _rule_counts(table: pd.DataFrame, p: SweepParams) -> dict[str, int]:
    """How many of ``table``'s configurations break each rig rule, by the rule's name."""
    lengths = list(LENGTHS[p.linkage_type])
    counts: dict[str, int] = {}
    for cfg in table[lengths].to_dict("records"):
        for r in (fourbar_rules if p.linkage_type == "four-bar" else slider_crank_rules)(**cfg):
            counts.setdefault(r.name.split(" (")[0], 0)
            counts[r.name.split(" (")[0]] += not r.ok
    return counts


def worst_markdown(table: pd.DataFrame, p: SweepParams, seconds: float | None = None) -> str:
    """The worst configurations and how they compare with the study's hand-found worst cases."""
    t = table.copy()
    ok = _ok(t).copy()
    joints = [f"peak_{j}_N" for j in JOINTS[p.linkage_type]]
    ok["max_reaction_N"] = ok[joints].max(axis=1)
    n_rules = int(t["rules_ok"].sum())
    assembles = t["status"] != "cannot assemble"
    lines = [f"# Sweep of every {p.linkage_type} configuration on the rig", "",
             f"Generated by `rigfem sweep --{p.linkage_type}` (speed {p.speed_hz:g} Hz, dynamics model "
             f"{p.model}, fidelity {p.fidelity}, {p.samples} crank angles, rails {list(p.rails)} mm, "
             f"ground rail {p.ground_mm:g} mm). Utilisation = peak von Mises / (σu/2) over every part "
             f"and both modes (the study's original load case and the real crank cycle). A configuration "
             f"*assembles* (closes over a full turn), *meets the rig rules* (geometry/RIG.md §2) and "
             f"*passes the stress criterion* (σu/2): three separate statements.", "",
             f"- configurations on the rig (each length on the 60 mm hole grid within its rail): {len(t)}",
             f"- do not assemble (cannot close over a full turn): {int((~assembles).sum())}",
             f"- assemble: {int(assembles.sum())}; of these pass a toggle (dead point, or transmission angle "
             f"within 5° of 0/180°; no stress number): {int((t['status'] == 'toggle').sum())}",
             f"- computed (assemble, no toggle): {len(ok)}; pass the stress criterion: "
             f"{int((ok['verdict'] == 'pass').sum())}, fail it: {int((ok['verdict'] == 'fail').sum())}, "
             f"undecided (the preset's error band contains the limit): {int((ok['verdict'] == 'undecided').sum())}",
             f"- meet the rig rules (geometry/RIG.md §2): {n_rules}; of these computed "
             f"{int(ok['rules_ok'].sum())}, failing the stress criterion "
             f"{int(((ok['verdict'] == 'fail') & ok['rules_ok']).sum())}"]
    if seconds is not None:
        lines.append(f"- compute wall time of this sweep (every run that computed chunks, unit solutions "
                     f"included): {seconds / 60:.1f} min")
    if ok.empty:
        return "\n".join(lines) + "\n"
    fixed = ok.attrs.get("fixed", {})
    lines += ["", "Rig rules broken by the configurations that assemble (count; one may break several):", ""]
    lines += [f"- {name}: {n}" for name, n in _rule_counts(t[assembles], p).items()]
    lines += ["", "Parts that limit the computed configurations (count):", ""]
    lines += [f"- {k}: {v}" for k, v in ok["limiting_part"].value_counts().items()]
    if fixed:
        lines += ["", "Cases whose utilisation is the same for every configuration (their load does not "
                  "depend on it): " + ", ".join(f"{_case(k)} {v:.1f} %" for k, v in fixed.items())
                  + ". The lists below rank by the highest utilisation of the other cases (*its utilisation*; "
                  "*limiting case* names it); *peak utilisation, every case* and the stress criterion's verdict "
                  "cover every case."]
    lines += ["", "Parts that limit the configuration-dependent utilisation (count):", ""]
    lines += [f"- {_case(k)}: {v}" for k, v in ok["config_limiting"].value_counts().items()]
    lines += ["", f"## The {WORST} worst configurations (highest utilisation)", "",
              _fmt(ok.nlargest(WORST, "config_util_pct"), p),
              f"## The {WORST} worst that meet the rig rules", "",
              _fmt(ok[ok["rules_ok"]].nlargest(WORST, "config_util_pct"), p),
              f"## The {WORST} largest peak reactions", "",
              _fmt(ok.nlargest(WORST, "max_reaction_N"), p)]
    lines += ["## Compared with the 2013 study's hand-found worst cases", "",
              "The study (geometry/RIG.md §3) found the largest reactions *for the smallest mechanisms* and *for "
              "transmission angles near the limits* by trying hypotheses by hand. On every computed "
              "configuration (Spearman rank correlation, −1..1):", ""]
    lengths = [c for c in LENGTHS[p.linkage_type] if c != "offset"]
    size = ok[lengths].sum(axis=1)
    for what, col in (("largest peak reaction", "max_reaction_N"), ("utilisation", "config_util_pct")):
        lines.append(f"- {what} vs mechanism size ({' + '.join(lengths)}): {_spearman(size, ok[col])}")
        lines += [f"  - vs {c}: {_spearman(ok[c], ok[col])}" for c in lengths]
        if p.linkage_type == "four-bar":
            margin = np.minimum(ok["mu_min_deg"], 180.0 - ok["mu_max_deg"])
            lines.append(f"  - vs transmission-angle margin min(μmin, 180° − μmax): {_spearman(margin, ok[col])}")
    if p.linkage_type == "four-bar":
        margin = np.minimum(ok["mu_min_deg"], 180.0 - ok["mu_max_deg"])
        bins = pd.cut(margin, [0, 15, 25, 35, 45, 90])
        med = ok.groupby(bins, observed=True)["max_reaction_N"].median()
        lines += ["", "Median of the largest peak reaction by transmission-angle margin:", "",
                  "| margin (deg) | configurations | median largest reaction (N) |", "|---|---:|---:|"]
        counts = bins.value_counts()
        lines += [f"| {k} | {int(counts[k])} | {v:.0f} |" for k, v in med.items()]
        r_mu = float(margin.rank().corr(ok["max_reaction_N"].rank()))
        r_size = float(size.rank().corr(ok["max_reaction_N"].rank()))
        top = ok.nlargest(WORST, "max_reaction_N")
        top_margin = margin[top.index]
        lines += ["", "Reading:", "",
                  f"- Transmission angles near the limits: rank correlation of the largest reaction with "
                  f"the margin {r_mu:+.2f} — "
                  + ("the study's finding holds over all configurations: the smaller the margin, the larger "
                     "the reactions; " if r_mu < -0.1 else "not a trend over all configurations; ")
                  + f"the {WORST} largest reactions have margins {top_margin.min():.1f}–{top_margin.max():.1f}° "
                  f"(all computed configurations: {margin.min():.1f}–{margin.max():.1f}°).",
                  f"- Smallest mechanisms: rank correlation with size {r_size:+.2f} — "
                  + ("the study's finding holds: smaller mechanisms give larger reactions."
                     if r_size < -0.1 else "the study's finding does not hold over all configurations."
                     if r_size > 0.1 else "no clear trend with overall size."),
                  f"- The {WORST} largest reactions have b2 = {top['b2'].min():g}–{top['b2'].max():g}, "
                  f"b3 = {top['b3'].min():g}–{top['b3'].max():g}, b4 = {top['b4'].min():g}–{top['b4'].max():g}, "
                  f"d = {top['d'].min():g}–{top['d'].max():g} mm."]
    return "\n".join(lines) + "\n"


def write_report(table: pd.DataFrame, p: SweepParams, out: Path, seconds: float | None = None) -> list[str]:
    """Write the CSV, the maps and worst_<type>.md into ``out``; returns the file names."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    csv = f"sweep_{p.linkage_type}.csv.gz"  # gzip: most rows are configurations that cannot assemble
    with whole_file(out / csv) as tmp:
        table.to_csv(tmp, index=False, float_format="%.6g", na_rep="",
                     compression={"method": "gzip", "mtime": 0})
    maps = write_maps(table, p, out)
    md = f"worst_{p.linkage_type}.md"
    text = worst_markdown(table, p, seconds)
    with whole_file(out / md) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return [csv] + maps + [md] + write_pages(table, p, out, text, maps)


def write_pages(table: pd.DataFrame, p: SweepParams, out: Path, markdown: str, maps: list[str]) -> list[str]:
    """The sweep's HTML page and the design-space explorer, from its table, Markdown and maps."""
    from rigfem.sweep.explorer import write_explorer

    page = f"sweep_{p.linkage_type}.html"
    with whole_file(out / page) as tmp:
        tmp.write_text(summary_html(markdown, maps, out, p), encoding="utf-8")
    write_explorer(out, {t: tab for t, tab in _tables(out, table, p).items()})
    return [page, EXPLORER]


def _tables(out: Path, table: pd.DataFrame, p: SweepParams) -> dict[str, pd.DataFrame]:
    """Both linkage types' tables for the explorer: this one, and the other's if the folder has it."""
    tables = {p.linkage_type: table}
    for t in LENGTHS:
        f = out / f"sweep_{t}.csv.gz"
        if t not in tables and f.is_file():
            tables[t] = pd.read_csv(f)
    return {t: tables[t] for t in LENGTHS if t in tables}  # always the same order: four-bar first


def summary_html(markdown: str, maps: list[str], out: Path, p: SweepParams) -> str:
    """One self-contained page: the sweep's Markdown (through mistune) and its maps embedded."""
    from rigfem.report.pages import markdown_html, png_uri, render_page

    return render_page("sweep.html.j2", kind=p.linkage_type, body=markdown_html(markdown),
                       maps=[(f, png_uri(out / f)) for f in maps], explorer=EXPLORER)
