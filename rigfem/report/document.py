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
from rigfem.report.figures import (allowable_label, asked_text, band, by_utilisation, number, part_label,
                                   safety_factor, sf_text, stopped_text)

#: version of report.json's layout (docs/guide/report.md: the fields); raised when a field changes meaning, goes or
#: is added (5: each part case's band_mpa and band_pct_of_allowable, the conclusion's band_mpa; 6: each part
#: case's mesh.asked, the settings' target_pct_of_peak, the cycle-mode picture of a part drawn in original mode;
#: 7: stress_verdict and standing, as the verdict stage decided them)
REPORT_SCHEMA = 7

#: the units of every number in a report
UNITS = [("length, position, displacement", "mm"), ("stress, strength, modulus", "MPa"), ("force", "N"),
         ("moment (part frame)", "N·mm"), ("driver torque", "N·m"), ("crank angle, transmission angle", "deg"),
         ("crank speed", "Hz"), ("mass", "kg"), ("density", "kg/m³"),
         ("utilisation (peak / allowable), error band, reserve", "%"), ("factor of safety", "–")]

#: what the model assumes and leaves out, whatever the scene
ASSUMPTIONS = [
    "Linear elasticity, small strain and small displacement: stress is proportional to load, so every part is "
    "solved once per unit load and the crank cycle is a superposition of those solutions.",
    "Quasi-static loads: the rigid-body dynamics of the linkage give the joint forces, the driver torque and each "
    "body's acceleration at every crank angle; the parts are loaded by them without vibration (no natural "
    "frequency, no impact, no play in the joints).",
    "No contact: a pin or screw pushes on the half of its hole it bears on, with a cosine pressure, and never "
    "pulls; parts do not touch each other.",
    "Screws and pins: a screw that holds a part is its hole wall on springs to a fixed rigid shaft; a pin or screw "
    "that loads a part is a bearing load on its hole; no preload, no thread, no friction.",
    "The material is homogeneous, isotropic and linear up to the criterion; no plasticity, residual stress or "
    "weld is modelled.",
    "The stress is the recovered nodal von Mises stress of the mesh (an estimate with a calibrated error band, "
    "not a bound); a sharp re-entrant corner's peak depends on the mesh.",
]


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
_PICTURE = {"von_mises": "von Mises as utilisation", "displacement": "displacement",
            "safety_factor": "factor of safety against the allowable"}


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
    return "(" + ", ".join(number(x, nd) for x in v) + ")"


def study_tables(r: dict) -> list[str]:
    """Markdown of the material, mesh and free-body balance tables."""
    lines = ["", f"## Material: {md_text(r['settings']['material'])}", "", "| property | value | unit | source |",
             "|---|---|---|---|"]
    for m in r.get("material", []):
        value = "–" if m["value"] is None else f"{m['value']:g}"
        lines.append(f"| {m['property']} | {value} | {m['unit']} | {md_text(m['source'])} |")
    parts = [p for p in r["parts"] if p.get("mesh")]
    lines += ["", "## Mesh per part", "", "| part | mode | element | nodes | elements | size at the peak (mm) | "
              "quality min (SICN, –) | asked (preset: target band, levels) | level | why it stopped | "
              "ladder: level DOF (s) |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for p in parts:
        m = p["mesh"]
        steps = ", ".join(f"{s['level']} {s['dofs']} ({s['seconds']:.1f})"
                          + "".join(f", {n} skipped" for n in s.get("skipped", [])) for s in m.get("ladder", []))
        lines.append(f"| {part_label(p['name'], p['part'])} | {p['mode']} | {m.get('element', '')} | {m.get('fe_nodes', m['nodes'])} | "
                     f"{m['tets']} | {number(m.get('size_at_peak_mm'), 2)} | {m['quality_min']:.2f} | {asked_text(p)} | "
                     f"{m.get('level', '')} | {m.get('stopped', '')} | {steps} |")
    lines += ["", "## Free-body balance per part (critical crank angle; moments about the part frame's origin; "
              "applied = pin loads and body forces, with the inertia relief of a free body)",
              "", "| part | mode | Σ applied F (N) | Σ applied M (N·mm) | Σ support reactions F (N) | "
              "Σ support reactions M (N·mm) | out of balance, force (N) |", "|---|---|---|---|---|---|---|"]
    for p in parts:
        b = p.get("balance")
        if b:
            free = " (free body: no support)" if any(k.startswith("FreeBody") for k in b.get("supports", {})) else ""
            lines.append(f"| {part_label(p['name'], p['part'])} | {p['mode']} | {_vec(b['applied_N'])} | "
                         f"{_vec(b['applied_Nmm'], 0)} | {_vec(b['supports_N'])}{free} | {_vec(b['supports_Nmm'], 0)} | "
                         f"{b['residual_N']:.2g} |")
    return lines


def _mesh_sizes(s: dict) -> str:
    """The preset's sizes, and with the adaptive ladder that they are the ceiling, not every part's mesh."""
    sizes = f"global size {s['size_mm']:g} mm, {s['local_size_mm']:g} mm at loaded interfaces"
    if not s.get("adaptive"):
        return sizes
    return (f"adaptive: each part refined from coarse up to {sizes}, only until its verdict is decided and its "
            f"band is within ±{s['target_pct']:g} % of the allowable{_of_peak(s)} (each part's level: "
            f"*Mesh per part*)")


def _of_peak(s: dict) -> str:
    """The preset's target in % of the peak as the settings state it (``fine``), "" when it has none."""
    t = s.get("target_pct_of_peak")
    return "" if t is None else f" and within ±{t:g} % of its own peak however far below the limit"


def _tolerance(r: dict) -> str:
    tol = {p["solve"]["imbalance"]["tolerance_pct"] for p in r["parts"] if p.get("solve")}
    return ", ".join(f"{t:g} %" for t in sorted(tol)) or "–"


def verdict_line(r: dict) -> str:
    """The verdict as the summary and the report print it: ``PASS (1 of 6 parts, original mode only)``."""
    checked = r.get("checked")
    return r["verdict"].upper() + (f" ({checked})" if checked else "")


def title_block(r: dict) -> list[str]:
    """Markdown of the title block: what was checked, when, by whom, with what (schema 4 and later)."""
    pv = r.get("provenance")
    if not pv:
        return ["", f"rigfem {md_text(r.get('rigfem_version', ''))} (report schema {r.get('schema', '–')}: "
                    f"no provenance recorded)"]
    commit = pv["commit"] + ("" if pv["dirty"] is None else " (dirty: uncommitted changes)" if pv["dirty"]
                             else " (clean)")
    libs = ", ".join(f"{k} {v}" for k, v in pv["libraries"].items())
    m = pv["machine"]
    rows = [("scene", r["scene"]), ("date (UTC)", pv["date_utc"]), ("author", pv["author"] or "–"),
            ("rigfem", f"{pv['rigfem_version']}, commit {commit}"), ("Python", pv["python"]), ("libraries", libs),
            ("machine", f"{m['host']}: {m['system']}, {m['cpu']}, {m['cores']} cores"),
            ("scene SHA-256", pv["scene_sha256"]), ("input SHA-256 (scene, [check] as run, reactions CSV)",
                                                     pv["input_sha256"])]
    return ["", "| title block | |", "|---|---|"] + [f"| {k} | {md_text(v)} |" for k, v in rows]


def conclusion_lines(r: dict) -> list[str]:
    """Markdown of the conclusion: the verdict, the governing part case, its utilisation with the
    band, the minimum factor of safety, the reserve, and what a check of a subset left out."""
    allowable = allowable_label(r["settings"]["limit_factor"], r["limit_mpa"])
    out = ["", "## Conclusion", "", f"**Overall verdict: {verdict_line(r)}** — the configuration {r['standing']}.",
           "", f"Stress criterion: **{r['stress_verdict'].upper()}** — peak von Mises < the {allowable} "
           f"({md_text(r['settings']['material'])}, σu = {r['settings']['sigma_u_mpa']:g} MPa)."]
    c = r.get("conclusion")
    if c:
        lo, hi = c["utilisation_band_pct"]
        out += ["", f"- governing: **{part_label(c['name'], c['part'])}, {c['mode']} mode** — "
                f"{c['verdict'].upper()}, peak σvm {c['peak_mpa']:.1f} MPa at crank {number(c['crank_deg'])}°",
                f"- utilisation {c['utilisation_pct']:.1f} % (band {lo:.1f}–{hi:.1f} %: "
                + (f"±{c['band_mpa']:.1f} MPa, ±{(hi - lo) / 2:.1f} % of the allowable, ±{c['error_pct']:.1f} % of "
                   f"the peak)" if "band_mpa" in c else f"±{(hi - lo) / 2:.1f} % of the allowable)"),
                f"- minimum factor of safety {sf_text(c['min_safety_factor'])} against the {allowable} "
                f"({sf_text(c['min_safety_factor_ultimate'])} against σu)",
                f"- reserve to the limit {c['reserve_pct']:.1f} % ({c['reserve_mpa']:.1f} MPa) at the band's top"]
    nc = r.get("not_checked") or {}
    if nc.get("parts") or nc.get("modes"):
        out.append("- **not checked**: " + "; ".join(
            t for t in (f"parts {md_text(', '.join(nc['parts']))}" if nc.get("parts") else "",
                        f"{' and '.join(nc['modes'])} mode" if nc.get("modes") else "") if t)
                   + " (this check covers " + md_text(r["checked"]) + ")")
    return out


def verdict_table(r: dict) -> list[str]:
    """Markdown of every part case, highest utilisation first, the governing one marked."""
    c = r.get("conclusion") or {}
    out = ["", "## Verdict per part case (highest utilisation first)", "",
           f"Factor of safety = {allowable_label(r['settings']['limit_factor'], r['limit_mpa']).split(' =')[0]} "
           f"/ peak von Mises (against the allowable; against σu it is twice that when the allowable is σu/2). "
           "The band is the peak's error estimate (an estimate, not a bound) three ways: ± MPa, ± % of the allowable "
           "(what the verdict reads) and ± % of the peak; *mesh stopped* says why the part's mesh was not refined "
           "further.", "",
           "| | part | mode | peak σvm (MPa) | utilisation (%) | band ± (MPa) | band ± (% of allowable) | "
           "band ± (% of peak) | verdict | factor of safety (–) | at crank (deg) | where (mm) | Goodman n (–) | "
           "mesh stopped |", "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for p in by_utilisation(r["parts"]):
        mark = "**▶ governing**" if (p["name"], p["mode"]) == (c.get("name"), c.get("mode")) else ""
        if p.get("peak_mpa") is None:
            out.append(f"| {mark} | {part_label(p['name'], p['part'])} | {p['mode']} | – | – | – | – | – | "
                       f"**{p['verdict'].upper()}** | – | – | – | – | – |")
            continue
        fat = p.get("fatigue")
        where = f"{p['surface']} ({', '.join(number(x) for x in p['location_mm'])})"
        sf = p.get("safety_factor", safety_factor(p["peak_mpa"], r["limit_mpa"]))
        b = band(p)
        out.append(f"| {mark} | {part_label(p['name'], p['part'])} | {p['mode']} | {p['peak_mpa']:.1f} | "
                   f"{p['utilisation_pct']:.1f} | ±{b['mpa']:.1f} | ±{b['pct_of_allowable']:.1f} | "
                   f"±{b['pct_of_peak']:.1f} | **{p['verdict'].upper()}** | {sf_text(sf)} | "
                   f"{number(p.get('crank_deg'))} | {where} | {sf_text(fat['safety_factor']) if fat else '–'} | "
                   f"{md_text(stopped_text(p))} |")
    minima = r.get("part_minima")
    if minima:
        out += ["", "Minimum factor of safety per part (over the modes checked):", "",
                "| part | against the allowable (–) | against σu (–) | in mode |", "|---|---|---|---|"]
        out += [f"| {part_label(m['name'], m['part'])} | {sf_text(m['min_safety_factor'])} | "
                f"{sf_text(m['min_safety_factor_ultimate'])} | {m['mode']} |" for m in minima]
    return out


def configuration_lines(r: dict) -> list[str]:
    """Markdown of the configuration, its rig rules and the peak reactions."""
    cfg = r["configuration"]
    lines = ["", "## Configuration", "",
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
                     f"{rule.get('unit', '') or '–'} | {'yes' if rule['ok'] else '**no**'} |")
    lines += ["", "## Peak reactions", "", "| joint | peak (N) | crank angle (deg) |", "|---|---|---|"]
    for name, p in r["peaks"].items():
        lines.append(f"| {name} | {number(p['force_N'])} | {number(p['crank_deg'], 2)} |")
    t = r["torque_Nm"]
    lines.append(f"| driver torque (N·m) | {number(t['peak'])} | {number(t['crank_deg'], 2)} |")
    return lines


def assumption_lines(r: dict) -> list[str]:
    """Markdown of the units table, the assumptions and limitations, and what each mode models."""
    out = ["", "## Units", "", "| quantity | unit |", "|---|---|"]
    out += [f"| {u['quantity']} | {u['unit']} |" for u in r.get("units") or [{"quantity": q, "unit": u}
                                                                          for q, u in UNITS]]
    out += ["", "## Assumptions and limitations", ""]
    out += [f"- {a}" for a in r.get("assumptions") or ASSUMPTIONS]
    out += [f"- {mode} mode: {MODE_TEXT[mode]}" for mode in r["settings"]["modes"]]
    return out


def _xyz(v) -> str:
    return " | ".join(number(x) for x in v)


def loads_lines(r: dict) -> list[str]:
    """Markdown of each part case's loads (every pin and screw force, the body force) and fixtures
    (every support's reaction) at its critical crank angle, in the part's frame."""
    cases = [p for p in r["parts"] if p.get("loads")]
    if not cases:
        return []
    out = ["", "## Loads and fixtures per part case (critical crank angle, part frame)", "",
           "Connector forces: each pin or screw that loads the part (a bearing load on the half of its hole it "
           "pushes) and each support's reaction. A free body (cycle-mode rail) has no support: its loads balance "
           "its own inertia, so its reactions are ≈ 0 by construction, not a missing load."]
    for p in cases:
        lf = p["loads"]
        out += ["", f"### {md_text(part_label(p['name'], p['part']))}, {p['mode']} mode, crank "
                    f"{lf['crank_deg']:.1f}°", "",
                "| entity | kind | Fx (N) | Fy (N) | Fz (N) | magnitude (N) |", "|---|---|---|---|---|---|"]
        out += [f"| {md_text(x['entity'])} | {x['kind']} | {_xyz(x['force_N'])} | {x['magnitude_N']:.1f} |"
                for x in lf["loads"]]
        out += [f"| {md_text(x['entity'])} | fixture: {x['kind']} | {_xyz(x['reaction_N'])} | "
                f"{x['magnitude_N']:.1f} |" for x in lf["fixtures"]]
        if lf.get("free_body"):
            out.append("")
            out.append("Free body: no support reactions (the 3-2-1 point supports only remove rigid motion).")
    return out


def notes_lines(r: dict) -> list[str]:
    """Markdown of every part case's notes."""
    rows = [(p, n) for p in r["parts"] for n in p.get("notes", [])]
    if not rows:
        return []
    return ["", "## Notes per part case", ""] + [f"- {p['name']} ({p['mode']}): {md_text(n)}" for p, n in rows]


def model_lines(r: dict) -> list[str]:
    """Markdown of the Model section: the mesh, what the band means and its calibration, the files."""
    lines = ["", "## Model", "",
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
    return lines


def warning_lines(r: dict) -> list[str]:
    """Markdown of the rule violations and assumed inputs, shown before anything else."""
    lines = []
    if r.get("rule_violations"):
        lines += ["", "**WARNING: this configuration does not meet the rig rules (geometry/RIG.md §2); it was "
                  "checked only because --allow-rule-violations was passed, and its overall verdict is FAIL "
                  "whatever its stresses. Rules broken:**", ""]
        lines += [f"- {md_text(v)}" for v in r["rule_violations"]]
    if r.get("assumed"):
        lines += ["", "**ASSUMED: the input lacked data the model needs; the scene stated its value:**", ""]
        lines += [f"- {md_text(v)}" for v in r["assumed"]]
    return lines


def render_markdown(r: dict) -> str:
    """The report as Markdown: title block, conclusion, verdicts by utilisation, configuration,
    assumptions, loads and fixtures, pictures, study tables, model."""
    lines = [f"# rigfem check: {md_text(r['scene'])}", "", md_text(r.get("description", "")).strip()]
    lines += title_block(r) + warning_lines(r) + conclusion_lines(r) + verdict_table(r)
    lines += configuration_lines(r) + assumption_lines(r) + loads_lines(r) + notes_lines(r)
    pics = [p for p in r["parts"] if p.get("pictures")]
    if pics:
        lines += ["", "## Pictures", "", "Stress pictures share one colour scale: utilisation 0–100 % of the "
                  f"{allowable_label(r['settings']['limit_factor'], r['limit_mpa'])}, magenta above it (the one map of "
                  f"utilisation in every picture and page); the factor of safety pictures divide the same allowable "
                  f"by the von Mises stress and are coloured as its utilisation (100 % / factor). Each picture's "
                  f"triad shows the part frame of the *where (mm)* column.", ""]
        for p in pics:
            label = part_label(p["name"], p["part"])
            lines += [f"![{md_text(label)}, {p['mode']} mode at crank {p['crank_deg']:.1f}°: {_PICTURE[k]}]({f})"
                      for k, f in p["pictures"]["files"].items()]
    if r.get("pictures"):
        lines += ["", "## Pictures", "", f"Pictures {r['pictures']}."]
    lines += study_tables(r)
    if r.get("differences"):
        lines += ["", "## Original vs cycle mode", ""] + [f"- {d}" for d in r["differences"]]
    lines += model_lines(r) + [""]
    return "\n".join(lines)


MODE_TEXT = {
    "original": ("As the 2013 study: peak reaction × load factor, resolved along and across the "
                 "rail, split over the two screws at the rail's far end (worst case), rail held by its "
                 "pivot coupling; plate loaded on its bearing seat; I-profile 250 N + 250 N per screw."),
    "cycle": ("What really happens: at every crank angle the actual joint forces through the actual "
              "coupling screws, the driver torque, and the bar's own inertia, with each rail analysed "
              "free in dynamic equilibrium; superposition of unit-load solutions."),
}
