"""The check report: one plain dict, written as ``report.json`` and rendered as ``report.md``.

The dict is the single source: the Markdown, the CLI summary and the pytest limits all read
it.  Every number in it is finite (:func:`finite` refuses NaN and infinity).
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

from rigfem.errors import plain

#: version of report.json's layout (README: report.json); raised when a field changes meaning or goes
REPORT_SCHEMA = 3


def finite(obj, where: str = "report"):
    """Return ``obj`` with numpy scalars made plain; raise if any number is NaN or infinite."""
    if isinstance(obj, dict):
        return {str(k): finite(v, f"{where}.{k}") for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite(v, f"{where}[{i}]") for i, v in enumerate(obj)]
    if hasattr(obj, "tolist"):  # numpy scalar or array
        return finite(obj.tolist(), where)
    if isinstance(obj, float) and not math.isfinite(obj):
        raise ValueError(f"{where} is {obj}: a non-finite number must never reach a report")
    return obj


def write_json(report: dict, path: Path) -> None:
    path.write_text(json.dumps(finite(report), indent=2) + "\n")


_MD_SPECIAL = re.compile(r"([\\`*_{}\[\]()#+\-.!|~>])")


def md_text(text: object) -> str:
    """User text (a scene's description, names) safe in Markdown and HTML: one line, no
    control characters, Markdown punctuation backslash-escaped, ``<``/``&`` as entities.

    >>> print(md_text("<b>*PASS*</b>"))
    &lt;b\\>\\*PASS\\*&lt;/b\\>
    """
    s = plain(text, 2000).replace("&", "&amp;").replace("<", "&lt;")
    return _MD_SPECIAL.sub(r"\\\1", s)


#: what each of a part's pictures shows (rigfem.report.pictures.part_pictures)
_PICTURE = {"von_mises": "von Mises as utilisation", "displacement": "displacement", "safety_factor": "factor of safety"}


def part_label(name: str, part: str) -> str:
    """The one name a reader sees for a part: its role and its catalogue name, ``crank_rail (rail_size25)``."""
    return f"{name} ({part})"


def allowable_label(limit_factor: float, limit_mpa: float) -> str:
    """The allowable stress written one way everywhere: ``allowable σu/2 = 375 MPa``."""
    sym = "σu/2" if limit_factor == 0.5 else f"{limit_factor:g}·σu"
    return f"allowable {sym} = {limit_mpa:.0f} MPa"


def material_table(m) -> list[dict]:
    """The material table of a report (rigfem.material.Material): each value with its unit and source."""
    from rigfem.material import material_sources

    src = material_sources(m)
    return [{"property": "E", "value": m.E, "unit": "MPa", "source": src["E"]},
            {"property": "nu", "value": m.nu, "unit": "-", "source": src["nu"]},
            {"property": "sigma_u", "value": m.sigma_u, "unit": "MPa", "source": src["sigma_u"]},
            {"property": "sigma_y", "value": None, "unit": "MPa", "source": src["sigma_y"]},
            {"property": "density", "value": m.density * 1e12, "unit": "kg/m³", "source": src["density"]}]


def _vec(v, nd: int = 1) -> str:
    return "(" + ", ".join(f"{round(x, nd) + 0.0:.{nd}f}" for x in v) + ")"


def study_tables(r: dict) -> list[str]:
    """Markdown of the material, mesh and free-body balance tables."""
    lines = ["", f"## Material: {md_text(r['settings']['material'])}", "", "| property | value | unit | source |",
             "|---|---|---|---|"]
    for m in r.get("material", []):
        value = "–" if m["value"] is None else f"{m['value']:g}"
        lines.append(f"| {m['property']} | {value} | {m['unit']} | {md_text(m['source'])} |")
    parts = [p for p in r["parts"] if p.get("mesh")]
    lines += ["", "## Mesh per part", "", "| part | mode | element | nodes | elements | size at the peak (mm) | "
              "quality min (SICN, –) | level | why it stopped | ladder: level DOF (s) |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for p in parts:
        m = p["mesh"]
        steps = ", ".join(f"{s['level']} {s['dofs']} ({s['seconds']:.1f})"
                          + "".join(f", {n} skipped" for n in s.get("skipped", [])) for s in m.get("ladder", []))
        lines.append(f"| {part_label(p['name'], p['part'])} | {p['mode']} | {m.get('element', '')} | {m.get('fe_nodes', m['nodes'])} | "
                     f"{m['tets']} | {_fmt(m.get('size_at_peak_mm'), 2)} | {m['quality_min']:.2f} | "
                     f"{m.get('level', '')} | {m.get('stopped', '')} | {steps} |")
    lines += ["", "## Free-body balance per part (critical crank angle; moments about the part frame's origin; "
              "applied = pin loads and body forces, with the inertia relief of a free body)",
              "", "| part | mode | Σ applied F (N) | Σ applied M (N·mm) | Σ support reactions F (N) | "
              "Σ support reactions M (N·mm) | out of balance, force (N) |", "|---|---|---|---|---|---|---|"]
    for p in parts:
        b = p.get("balance")
        if b:
            lines.append(f"| {part_label(p['name'], p['part'])} | {p['mode']} | {_vec(b['applied_N'])} | "
                         f"{_vec(b['applied_Nmm'], 0)} | {_vec(b['supports_N'])} | {_vec(b['supports_Nmm'], 0)} | "
                         f"{b['residual_N']:.2g} |")
    return lines


def _fmt(x, nd: int = 1) -> str:
    return "–" if x is None else f"{x:.{nd}f}"


def _mesh_sizes(s: dict) -> str:
    """The preset's sizes, and with the adaptive ladder that they are the ceiling, not every part's mesh."""
    sizes = f"global size {s['size_mm']:g} mm, {s['local_size_mm']:g} mm at loaded interfaces"
    if not s.get("adaptive"):
        return sizes
    return (f"adaptive: each part refined from coarse up to {sizes}, only until its verdict is decided and its "
            f"band is within ±{s['target_pct']:g} % of the allowable (each part's level: *Mesh per part*)")


def _tolerance(r: dict) -> str:
    tol = {p["solve"]["imbalance"]["tolerance_pct"] for p in r["parts"] if p.get("solve")}
    return ", ".join(f"{t:g} %" for t in sorted(tol)) or "–"


def render_markdown(r: dict) -> str:
    """Human-readable report: configuration, rules, reactions, one table per mode."""
    cfg = r["configuration"]
    lines = [f"# rigfem check: {md_text(r['scene'])}", ""]
    if r.get("rule_violations"):
        lines += ["**WARNING: this configuration breaks rig rules and cannot be mounted as given; it was "
                  "checked only because --allow-rule-violations was passed, and its overall verdict is FAIL "
                  "whatever its stresses:**", ""]
        lines += [f"- {md_text(v)}" for v in r["rule_violations"]] + [""]
    if r.get("assumed"):
        lines += ["**ASSUMED: the input lacked data the model needs; the scene stated its value:**", ""]
        lines += [f"- {md_text(v)}" for v in r["assumed"]] + [""]
    lines += [
             md_text(r.get("description", "")).strip(), "",
             f"**Overall verdict: {r['verdict'].upper()}** — criterion: peak von Mises < the "
             f"{allowable_label(r['settings']['limit_factor'], r['limit_mpa'])} "
             f"({md_text(r['settings']['material'])}).", ""]
    lines += ["## Configuration", "",
              f"- linkage: {cfg['type']}, lengths (mm): "
              + ", ".join(f"{k} = {v:g}" for k, v in cfg["lengths_mm"].items())
              + (f", branch {cfg['branch']}" if cfg.get("branch") else ""),
              f"- crank speed {cfg['speed_hz']:g} Hz, mass model `{cfg['model']}`, "
              f"{cfg['samples']} samples per turn (peaks refined)"]
    if r.get("transmission_angle_deg"):
        mu = r["transmission_angle_deg"]
        lines.append(f"- transmission angle μ: {mu['min']:.2f}° … {mu['max']:.2f}°")
    if r.get("singular"):
        lines.append(f"- **toggle (singular) crank-angle ranges: {r['singular']}** — reactions there "
                     f"are not reported")
    lines += ["", "| rule | value | limit | unit | ok |", "|---|---|---|---|---|"]
    for rule in r.get("rules", []):
        lines.append(f"| {rule['name']} | {rule['value']:.6g} | {rule.get('relation', '')} {rule['limit']:.6g} | "
                     f"{rule.get('unit', '')} | {'yes' if rule['ok'] else '**no**'} |")
    lines += ["", "## Peak reactions", "", "| joint | peak (N) | crank angle (°) |", "|---|---|---|"]
    for name, p in r["peaks"].items():
        lines.append(f"| {name} | {_fmt(p['force_N'])} | {_fmt(p['crank_deg'], 2)} |")
    t = r["torque_Nm"]
    lines.append(f"| driver torque (N·m) | {_fmt(t['peak'])} | {_fmt(t['crank_deg'], 2)} |")
    for mode in r["settings"]["modes"]:
        rows = [p for p in r["parts"] if p["mode"] == mode]
        lines += ["", f"## Parts, {mode} mode", "", MODE_TEXT[mode], "",
                  "| part | peak σvm (MPa) | at crank (°) | where (mm) | error est. | utilisation | "
                  "verdict | Goodman n (–) |", "|---|---|---|---|---|---|---|---|"]
        for p in rows:
            fat = p.get("fatigue")
            if p.get("peak_mpa") is None:
                lines.append(f"| {part_label(p['name'], p['part'])} | – | – | – | – | – | **{p['verdict']}** | – |")
                continue
            lines.append(
                f"| {part_label(p['name'], p['part'])} | {p['peak_mpa']:.1f} | {_fmt(p.get('crank_deg'), 1)} | "
                f"{p['surface']} ({', '.join(f'{c:.1f}' for c in p['location_mm'])}) | "
                f"±{p['error_pct']:.1f} % | {p['utilisation_pct']:.1f} % | **{p['verdict']}** | "
                f"{_fmt(fat['safety_factor'], 2) if fat else '–'} |")
        for p in rows:
            for note in p.get("notes", []):
                lines.append(f"- {p['name']}: {note}")
    pics = [p for p in r["parts"] if p.get("pictures")]
    if pics:
        lines += ["", "## Pictures", "", "Stress pictures share one colour scale: utilisation 0–100 % of the "
                  f"{allowable_label(r['settings']['limit_factor'], r['limit_mpa'])}, magenta above it.", ""]
        for p in pics:
            label = part_label(p["name"], p["part"])
            lines += [f"![{md_text(label)}: {_PICTURE[k]}]({f})" for k, f in p["pictures"]["files"].items()]
    if r.get("pictures"):
        lines += ["", "## Pictures", "", f"Pictures {r['pictures']}."]
    lines += study_tables(r)
    if r.get("differences"):
        lines += ["", "## Original vs cycle mode", ""] + [f"- {d}" for d in r["differences"]]
    lines += ["", "## Model", "",
              f"- fidelity `{r['settings']['fidelity']}`: P{r['settings']['order']} tetrahedra, "
              + _mesh_sizes(r['settings']),
              "- error estimate (an estimate, not a bound): recovery-based (difference between the raw and the "
              "recovered stress at the peak) times a per-order factor calibrated so the band covers the converged "
              "peak (results/convergence/band_coverage.md); a peak whose band contains the limit is *undecided*",
              "- free-body imbalance (force, moment; relative to the applied load, tolerance "
              f"{_tolerance(r)}): " + "; ".join(f"{p['name']} {p['mode']} {p['solve']['imbalance']['force_pct']:.2f} %, "
                                                f"{p['solve']['imbalance']['moment_pct']:.2f} %"
                                                for p in r["parts"] if p.get("solve")),
              f"- files: {', '.join(r.get('files', []))}"]
    if r.get("field_files"):
        lines.append(f"- written by the run for ParaView/CalculiX, not kept in the repository's result folders "
                     f"(`rigfem check --force` writes them again): {', '.join(r['field_files'])}")
    lines.append("")
    return "\n".join(lines)


MODE_TEXT = {
    "original": ("As the 2013 study: peak reaction × load factor, resolved along and across the "
                 "rail, split over the two screws at the rail's far end (worst case), rail held by its "
                 "pivot coupling; plate loaded on its bearing seat; I-profile 250 N + 250 N per screw."),
    "cycle": ("What really happens: at every crank angle the actual joint forces through the actual "
              "coupling screws, the driver torque, and the bar's own inertia, with each rail analysed "
              "free in dynamic equilibrium; superposition of unit-load solutions."),
}
