"""What a sweep table says: utilisation maps (PNG) and the worst configurations (Markdown).

The worst list is set beside the 2013 study's hand-found worst cases (geometry/RIG.md §3: the largest
reactions for the smallest mechanisms and for transmission angles near the limits), with the
rank correlations that test both statements on every configuration the sweep computed.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from rigfem.files import whole_file
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


def write_maps(table: pd.DataFrame, p: SweepParams, out: Path) -> list[str]:
    """PNG maps of the peak utilisation over the lengths; returns the file names."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = _ok(table)
    if ok.empty or "config_util_pct" not in ok:
        return []
    from rigfem.report.scale import UTILISATION_SCALE_PCT, colormap

    vmin, vmax = UTILISATION_SCALE_PCT  # the report's one scale: yellow is 100 %, magenta above, everywhere
    cmap = colormap()
    fixed = ", ".join(f"{k} {v:.1f} %" for k, v in ok.attrs.get("fixed", {}).items())
    note = f" (not shown, the same everywhere: {fixed})" if fixed else ""
    files = []
    if p.linkage_type == "four-bar":
        for (x, y, over), name in ((("d", "b3", "b4"), "d_b3"), (("b4", "b3", "d"), "b4_b3")):
            b2s = sorted(table["b2"].unique())
            cols = 3
            fig, axes = plt.subplots(int(np.ceil(len(b2s) / cols)), cols, figsize=(13, 3.6 * np.ceil(len(b2s) / cols)),
                                     squeeze=False, sharex=True, sharey=True)
            xs, ys = sorted(table[x].unique()), sorted(table[y].unique())
            im = None
            for ax, b2 in zip(axes.flat, b2s):
                sub = ok[ok["b2"] == b2].groupby([y, x])["config_util_pct"].max().unstack()
                grid = sub.reindex(index=ys, columns=xs).to_numpy(dtype=float)
                im = ax.imshow(np.ma.masked_invalid(grid), origin="lower", aspect="auto", vmin=vmin, vmax=vmax,
                               cmap=cmap, extent=(xs[0] - 30, xs[-1] + 30, ys[0] - 30, ys[-1] + 30))
                if np.nanmax(np.nan_to_num(grid, nan=0.0)) >= 100.0:
                    ax.contour(xs, ys, np.nan_to_num(grid, nan=0.0), levels=[100.0], colors="r")
                # computed but not mountable (a rig rule broken): hatched; failing: red outline
                bad = ok[(ok["b2"] == b2) & ~ok["rules_ok"].astype(bool)].groupby([y, x]).size().unstack()
                bad = bad.reindex(index=ys, columns=xs).notna().to_numpy()
                fail = ok[(ok["b2"] == b2) & (ok["verdict"] != "pass")].groupby([y, x]).size().unstack()
                fail = fail.reindex(index=ys, columns=xs).notna().to_numpy()
                for (i, j) in zip(*np.nonzero(bad)):
                    ax.add_patch(plt.Rectangle((xs[j] - 30, ys[i] - 30), 60, 60, fill=False, hatch="///",
                                               edgecolor="white", lw=0))
                for (i, j) in zip(*np.nonzero(fail)):
                    ax.add_patch(plt.Rectangle((xs[j] - 30, ys[i] - 30), 60, 60, fill=False, edgecolor="red", lw=1.2))
                if b2 == FINAL_DESIGN["b2"]:
                    ax.plot(FINAL_DESIGN[x], FINAL_DESIGN[y], marker="*", ms=14, color="white", mec="k")
                ax.set_facecolor("0.85")
                ax.set_title(f"b2 = {b2:g} mm", fontsize="small")
            for ax in axes.flat[len(b2s):]:
                ax.axis("off")
            for ax in axes[-1]:
                ax.set_xlabel(f"{x} (mm)")
            for ax in axes[:, 0]:
                ax.set_ylabel(f"{y} (mm)")
            fig.colorbar(im, ax=axes, shrink=0.6, extend="max",
                         label=f"peak utilisation (%), max over {over}; magenta: above 100 %")
            fig.suptitle(f"four-bar: peak part utilisation vs σu/2 ({p.speed_hz:g} Hz, {p.model}, {p.fidelity}){note}\n"
                         f"grey: cannot assemble or toggle; hatched: breaks a rig rule (not mountable); "
                         f"red outline: fails or undecided; ★ the study's final design", fontsize="small")
            f = f"map_four-bar_{name}.png"
            with whole_file(out / f) as tmp:
                fig.savefig(tmp, dpi=90)
            plt.close(fig)
            files.append(f)
    else:
        xs, ys = sorted(table["b2"].unique()), sorted(table["b3"].unique())
        grid = ok.groupby(["b3", "b2"])["config_util_pct"].max().unstack().reindex(index=ys, columns=xs)
        fig, ax = plt.subplots(figsize=(6, 5))
        im = ax.imshow(np.ma.masked_invalid(grid.to_numpy(dtype=float)), origin="lower", aspect="auto", cmap=cmap,
                       vmin=vmin, vmax=vmax, extent=(xs[0] - 30, xs[-1] + 30, ys[0] - 30, ys[-1] + 30))
        ax.set_facecolor("0.85")
        ax.set_xlabel("b2 (mm)"), ax.set_ylabel("b3 (mm)")
        fig.colorbar(im, extend="max", label="peak utilisation (%); magenta: above 100 %")
        ax.set_title(f"slider-crank: peak part utilisation, {p.speed_hz:g} Hz{note}", fontsize="x-small")
        f = "map_slider-crank_b2_b3.png"
        with whole_file(out / f) as tmp:
            fig.savefig(tmp, dpi=90)
        plt.close(fig)
        files.append(f)
    return files


def _spearman(a: pd.Series, b: pd.Series) -> str:
    r = a.rank().corr(b.rank())
    return "n/a" if not np.isfinite(r) else f"{r:+.2f}"


def _fmt(df: pd.DataFrame, p: SweepParams) -> str:
    cols = [*LENGTHS[p.linkage_type]] + (["mu_min_deg", "mu_max_deg"] if p.linkage_type == "four-bar" else [])
    cols += ["rules_ok", "max_reaction_N", "peak_torque_Nm", "config_limiting", "config_util_pct",
             "limiting_part", "max_util_pct", "verdict"]
    head = "| " + " | ".join(cols) + " |\n|" + "---|" * len(cols) + "\n"
    lines = []
    for _, r in df.iterrows():
        cells = []
        for c in cols:
            v = r[c]
            cells.append("yes" if v is True or v is np.True_ else "no" if v is False or v is np.False_
                         else f"{v:.1f}" if isinstance(v, float) else str(v))
        lines.append("| " + " | ".join(cells) + " |")
    return head + "\n".join(lines) + "\n"


def worst_markdown(table: pd.DataFrame, p: SweepParams, seconds: float | None = None) -> str:
    """The worst configurations and how they compare with the study's hand-found worst cases."""
    t = table.copy()
    ok = _ok(t).copy()
    joints = [f"peak_{j}_N" for j in JOINTS[p.linkage_type]]
    ok["max_reaction_N"] = ok[joints].max(axis=1)
    n_rules = int(t["rules_ok"].sum())
    lines = [f"# Sweep of every mountable {p.linkage_type} configuration", "",
             f"Generated by `rigfem sweep --{p.linkage_type}` (speed {p.speed_hz:g} Hz, dynamics model "
             f"{p.model}, fidelity {p.fidelity}, {p.samples} crank angles, rails {list(p.rails)} mm, "
             f"ground rail {p.ground_mm:g} mm). Utilisation = peak von Mises / (σu/2) over every part "
             f"and both modes (the study's original load case and the real crank cycle).", "",
             f"- mountable configurations (lengths on the 60 mm grid within the rails): {len(t)}",
             f"- cannot be assembled over a full turn: {int((t['status'] == 'cannot assemble').sum())}",
             f"- toggle (dead point, or transmission angle within 5° of 0/180°; no number): {int((t['status'] == 'toggle').sum())}",
             f"- computed: {len(ok)}; pass: {int((ok['verdict'] == 'pass').sum())}, "
             f"fail: {int((ok['verdict'] == 'fail').sum())}, undecided (the preset's error band "
             f"contains the limit): {int((ok['verdict'] == 'undecided').sum())}",
             f"- comply with every rig rule (geometry/RIG.md §2): {n_rules}; of these computed "
             f"{int(ok['rules_ok'].sum())}, failing the stress criterion "
             f"{int(((ok['verdict'] == 'fail') & ok['rules_ok']).sum())}"]
    if seconds is not None:
        lines.append(f"- compute wall time of this sweep (every run that computed chunks, unit solutions "
                     f"included): {seconds / 60:.1f} min")
    if ok.empty:
        return "\n".join(lines) + "\n"
    fixed = ok.attrs.get("fixed", {})
    lines += ["", "Parts that limit the computed configurations (count):", ""]
    lines += [f"- {k}: {v}" for k, v in ok["limiting_part"].value_counts().items()]
    if fixed:
        lines += ["", "Cases whose utilisation is the same for every configuration (their load does not "
                  "depend on it): " + ", ".join(f"{k} {v:.1f} %" for k, v in fixed.items())
                  + ". The lists below rank by `config_util_pct`, the highest utilisation of the other "
                  "cases (`config_limiting` names it); `max_util_pct` and the verdict cover every case."]
    lines += ["", "Parts that limit the configuration-dependent utilisation (count):", ""]
    lines += [f"- {k}: {v}" for k, v in ok["config_limiting"].value_counts().items()]
    lines += ["", f"## The {WORST} worst configurations (highest utilisation)", "",
              _fmt(ok.nlargest(WORST, "config_util_pct"), p),
              f"## The {WORST} worst that comply with every rig rule", "",
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
