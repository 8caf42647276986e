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


def _fmt(x, nd: int = 1) -> str:
    return "–" if x is None else f"{x:.{nd}f}"


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
             f"**Overall verdict: {r['verdict'].upper()}** — criterion σvm,peak < "
             f"{r['settings']['limit_factor']:g}·σu = {r['limit_mpa']:.0f} MPa "
             f"({md_text(r['settings']['material'])}).", ""]
    lines += ["## Configuration", "",
              f"- linkage: {cfg['type']}, lengths (mm): "
              + ", ".join(f"{k} = {v:g}" for k, v in cfg["lengths_mm"].items()),
              f"- crank speed {cfg['speed_hz']:g} Hz, mass model `{cfg['model']}`, "
              f"{cfg['samples']} samples per turn (peaks refined)"]
    if r.get("transmission_angle_deg"):
        mu = r["transmission_angle_deg"]
        lines.append(f"- transmission angle μ: {mu['min']:.2f}° … {mu['max']:.2f}°")
    if r.get("singular"):
        lines.append(f"- **toggle (singular) crank-angle ranges: {r['singular']}** — reactions there "
                     f"are not reported")
    lines += ["", "| rule | value | limit | ok |", "|---|---|---|---|"]
    for rule in r.get("rules", []):
        lines.append(f"| {rule['name']} | {rule['value']:.6g} | {rule['limit']:.6g} | "
                     f"{'yes' if rule['ok'] else '**no**'} |")
    lines += ["", "## Peak reactions", "", "| joint | peak (N) | crank angle (°) |", "|---|---|---|"]
    for name, p in r["peaks"].items():
        lines.append(f"| {name} | {_fmt(p['force_N'])} | {_fmt(p['crank_deg'], 2)} |")
    t = r["torque_Nm"]
    lines.append(f"| driver torque (N·m) | {_fmt(t['peak'])} | {_fmt(t['crank_deg'], 2)} |")
    for mode in r["settings"]["modes"]:
        rows = [p for p in r["parts"] if p["mode"] == mode]
        lines += ["", f"## Parts, {mode} mode", "", MODE_TEXT[mode], "",
                  "| part | peak σvm (MPa) | at crank (°) | where | error est. | utilisation | "
                  "verdict | Goodman n |", "|---|---|---|---|---|---|---|---|"]
        for p in rows:
            fat = p.get("fatigue")
            if p.get("peak_mpa") is None:
                lines.append(f"| {p['name']} ({p['part']}) | – | – | – | – | – | **{p['verdict']}** | – |")
                continue
            lines.append(
                f"| {p['name']} ({p['part']}) | {p['peak_mpa']:.1f} | {_fmt(p.get('crank_deg'), 1)} | "
                f"{p['surface']} ({', '.join(f'{c:.1f}' for c in p['location_mm'])}) | "
                f"±{p['error_pct']:.1f} % | {p['utilisation_pct']:.1f} % | **{p['verdict']}** | "
                f"{_fmt(fat['safety_factor'], 2) if fat else '–'} |")
        for p in rows:
            for note in p.get("notes", []):
                lines.append(f"- {p['name']}: {note}")
    if r.get("differences"):
        lines += ["", "## Original vs cycle mode", ""] + [f"- {d}" for d in r["differences"]]
    lines += ["", "## Model", "",
              f"- fidelity `{r['settings']['fidelity']}`: P{r['settings']['order']} tetrahedra, "
              f"global size {r['settings']['size_mm']:g} mm, {r['settings']['local_size_mm']:g} mm at "
              f"loaded interfaces",
              "- error estimate (an estimate, not a bound): recovery-based (difference between the raw and the "
              "recovered stress at the peak) times a per-order factor calibrated so the band covers the converged "
              "peak (results/convergence/band_coverage.md); a peak whose band contains the limit is *undecided*",
              "- free-body imbalance (force, moment; relative to the applied load, tolerance "
              f"{_tolerance(r)}): " + "; ".join(f"{p['name']} {p['mode']} {p['solve']['imbalance']['force_pct']:.2f} %, "
                                                f"{p['solve']['imbalance']['moment_pct']:.2f} %"
                                                for p in r["parts"] if p.get("solve")),
              f"- files: {', '.join(r.get('files', []))}", ""]
    return "\n".join(lines)


MODE_TEXT = {
    "original": ("As the 2013 study: peak reaction × load factor, resolved along and across the "
                 "rail, split over the two screws at the rail's far end (worst case), rail held by its "
                 "pivot coupling; plate loaded on its bearing seat; I-profile 250 N + 250 N per screw."),
    "cycle": ("What really happens: at every crank angle the actual joint forces through the actual "
              "coupling screws, the driver torque, and the bar's own inertia, with each rail analysed "
              "free in dynamic equilibrium; superposition of unit-load solutions."),
}
