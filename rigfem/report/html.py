"""``report.html``: the check report as one self-contained page (pictures embedded).

Built from the report dict and the picture files of the result folder only, so the page
carries exactly the numbers of ``report.json``.  Every text that can come from a user's file
(scene description, names, notes) is HTML-escaped.  Opens in any browser without a server.
"""

from __future__ import annotations

import base64
import html
from pathlib import Path

from rigfem.report.document import MODE_TEXT

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:2em auto;max-width:1200px;
     color:#1b1b1b;line-height:1.45;padding:0 1em}
h1{margin-bottom:.2em} h2{border-bottom:2px solid #ddd;padding-bottom:.2em;margin-top:1.6em}
table{border-collapse:collapse;margin:.6em 0;font-size:.93em} th,td{border:1px solid #ccc;padding:.3em .6em}
th{background:#f3f3f3;text-align:left} td.num{text-align:right;font-variant-numeric:tabular-nums}
.badge{display:inline-block;padding:.15em .6em;border-radius:.3em;color:#fff;font-weight:700}
.pass{background:#2e7d32}.fail{background:#c62828}.undecided{background:#ef6c00}
.big{font-size:1.5em} img{max-width:100%;border:1px solid #ddd;margin:.4em 0}
.bar{background:#eee;width:160px;height:.8em;display:inline-block;position:relative;vertical-align:middle}
.bar span{position:absolute;top:0;bottom:0;background:#1565c0}.bar i{position:absolute;top:0;bottom:0;
     background:rgba(21,101,192,.35)} .note{color:#555;font-size:.92em} code{background:#f3f3f3;padding:0 .2em}
"""


def _e(x) -> str:
    return html.escape(str(x), quote=True)


def _num(x, digits: int) -> str:
    """A number, or a dash where there is none (a toggle has no peak)."""
    return "–" if x is None else f"{x:.{digits}f}"


def _badge(verdict: str, big: bool = False) -> str:
    v = str(verdict)
    return f'<span class="badge {_e(v)}{" big" if big else ""}">{_e(v.upper())}</span>'


def _img(folder: Path, name: str, alt: str) -> str:
    """An embedded PNG (data URI), or nothing if the file is absent."""
    path = folder / name
    if not path.is_file():
        return ""
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return f'<img src="data:image/png;base64,{data}" alt="{_e(alt)}" data-file="{_e(name)}">'


def _util_bar(p: dict) -> str:
    """Utilisation bar with its error-estimate band (0..120 % of the allowable)."""
    u, e = p["utilisation_pct"], p["error_pct"]
    lo, hi = u * (1 - e / 100), u * (1 + e / 100)
    w = lambda x: f"{min(max(x, 0.0), 120.0) / 1.2:.1f}%"
    return (f'<span class="bar" title="{lo:.1f}–{hi:.1f} %"><i style="left:{w(lo)};width:'
            f'{min(max(hi, 0), 120) / 1.2 - min(max(lo, 0), 120) / 1.2:.1f}%"></i>'
            f'<span style="left:0;width:{w(u)}"></span></span>')


def _kv(rows: list[tuple[str, str]]) -> str:
    return "<table>" + "".join(f"<tr><th>{_e(k)}</th><td>{v}</td></tr>" for k, v in rows) + "</table>"


def render_html(report: dict, folder: str | Path) -> str:
    """The HTML page of a check report whose pictures lie in ``folder``."""
    folder = Path(folder)
    r = report
    cfg, s = r["configuration"], r["settings"]
    out = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
           f"<title>rigfem check: {_e(r['scene'])}</title><style>{_CSS}</style></head><body>",
           f"<h1>rigfem check: {_e(r['scene'])}</h1>"]
    if r.get("description"):
        out.append(f'<p class="note">{_e(r["description"])}</p>')
    out.append(f"<p>Overall verdict {_badge(r['verdict'], big=True)} &nbsp; criterion: peak von Mises "
               f"&lt; {s['limit_factor']:g}·σu = <b>{r['limit_mpa']:.0f} MPa</b> "
               f"({_e(s['material'])}, σu = {s['sigma_u_mpa']:g} MPa); utilisation = peak / allowable, "
               f"with the peak's discretisation-error estimate as a band (an estimate, not a bound).</p>")
    if r.get("rule_violations"):
        out.append("<p><b>NOT MOUNTABLE: this configuration breaks rig rules and was checked only because "
                   "--allow-rule-violations was passed; its overall verdict is FAIL whatever its stresses.</b></p><ul>"
                   + "".join(f"<li>{_e(v)}</li>" for v in r["rule_violations"]) + "</ul>")
    for w in r.get("warnings") or []:
        out.append(f'<p class="note">⚠ {_e(w)}</p>')
    if r.get("singular"):
        out.append(f"<p><b>Toggle (singular) crank-angle ranges {_e(r['singular'])}</b>: the reactions grow "
                   f"without bound there; no stress is computed.</p>")
    # verdict per part
    out += ["<h2>Verdict per part</h2>", "<table><tr><th>part</th><th>mode</th><th>peak σvm (MPa)</th>"
            "<th>error est.</th><th>utilisation</th><th></th><th>verdict</th><th>crank angle (°)</th>"
            "<th>where (mm)</th><th>Goodman n</th></tr>"]
    for p in r["parts"]:
        if p.get("peak_mpa") is None:
            out.append(f"<tr><td>{_e(p['name'])}</td><td>{_e(p['mode'])}</td><td colspan=5>–</td>"
                       f"<td>{_badge(p['verdict'])}</td><td colspan=2>–</td></tr>")
            continue
        fat = p.get("fatigue")
        loc = ", ".join(f"{c:.1f}" for c in p["location_mm"])
        out.append(
            f"<tr><td>{_e(p['name'])} <span class=note>({_e(p['part'])})</span></td><td>{_e(p['mode'])}</td>"
            f"<td class=num>{p['peak_mpa']:.1f}</td><td class=num>±{p['error_pct']:.1f} %</td>"
            f"<td class=num>{p['utilisation_pct']:.1f} %</td><td>{_util_bar(p)}</td><td>{_badge(p['verdict'])}</td>"
            f"<td class=num>{p['crank_deg']:.1f}</td><td>{_e(p['surface'])} ({loc})</td>"
            f"<td class=num>{'%.2f' % fat['safety_factor'] if fat else '–'}</td></tr>")
    out.append("</table>")
    out.append('<p><a href="report.json">report.json</a> · <a href="report.md">report.md</a></p>')
    # the scene and the settings that shaped the result
    lengths = ", ".join(f"{_e(k)} = {v:g}" for k, v in cfg["lengths_mm"].items())
    rows = [("linkage", f"{_e(cfg['type'])}: {lengths} mm"),
            ("crank speed", f"{cfg['speed_hz']:g} Hz"), ("mass model", _e(cfg["model"])),
            ("crank angles per turn", f"{cfg['samples']} (peaks refined between samples)")]
    if r.get("transmission_angle_deg"):
        mu = r["transmission_angle_deg"]
        rows.append(("transmission angle", f"{mu['min']:.2f}° … {mu['max']:.2f}°"))
    rows += [("modes", _e(", ".join(s["modes"]))), ("fidelity", _e(s["fidelity"])),
             ("elements", f"P{s['order']} tetrahedra (curved), {s['size_mm']:g} mm, "
                          f"{s['local_size_mm']:g} mm at loaded interfaces"),
             ("bearing directions", f"{s['bearing_directions']}"),
             ("load factor (original mode)", f"{s['load_factor']:g}"),
             ("fatigue", _e(", ".join(f"{k} = {v}" for k, v in s["fatigue"].items()))),
             ("rigfem", _e(r.get("rigfem_version", "")))]
    out += ["<h2>Scene and settings</h2>", _kv(rows)]
    if r.get("rules"):
        out.append("<table><tr><th>rig rule</th><th>value</th><th>limit</th><th>ok</th></tr>")
        for rule in r["rules"]:
            out.append(f"<tr><td>{_e(rule['name'])}</td><td class=num>{rule['value']:.6g}</td>"
                       f"<td class=num>{_e(rule['relation'])} {rule['limit']:.6g}</td>"
                       f"<td>{'yes' if rule['ok'] else '<b>no</b>'}</td></tr>")
        out.append("</table>")
    # reactions and torque
    out += ["<h2>Pin reactions and driver torque</h2>",
            "<table><tr><th>joint</th><th>peak (N)</th><th>at crank (°)</th></tr>"]
    for name, pk in r["peaks"].items():
        out.append(f"<tr><td>{_e(name)}</td><td class=num>{_num(pk.get('force_N'), 1)}</td>"
                   f"<td class=num>{_num(pk.get('crank_deg'), 2)}</td></tr>")
    t = r.get("torque_Nm")
    if t:
        out.append(f"<tr><td>driver torque (N·m)</td><td class=num>{_num(t.get('peak'), 1)}</td>"
                   f"<td class=num>{_num(t.get('crank_deg'), 2)}</td></tr>")
    out.append("</table>")
    out.append(_img(folder, "reactions.png", "pin reactions and driver torque over the crank turn"))
    out.append(_img(folder, "peak_von_mises.png", "peak von Mises stress per part over the crank cycle"))
    # per part
    out.append("<h2>Parts</h2>")
    for mode in s["modes"]:
        out.append(f'<p class="note"><b>{_e(mode)} mode</b>: {_e(MODE_TEXT.get(mode, ""))}</p>')
    for name in dict.fromkeys(p["name"] for p in r["parts"]):
        ps = [p for p in r["parts"] if p["name"] == name]
        out.append(f"<h3>{_e(name)} ({_e(ps[0]['part'])})</h3>")
        out.append(_img(folder, f"{name}.png", f"von Mises field of {name}"))
        out.append(_img(folder, f"{name}_utilisation.png", f"utilisation of {name} over the crank cycle"))
        out.append(_img(folder, f"{name}_displacement.png", f"displacement of {name}"))
        out.append(_img(folder, f"{name}_safety_factor.png", f"factor of safety of {name}"))
        for p in ps:
            if p.get("peak_mpa") is None:
                continue
            items = [("peak", f"{p['peak_mpa']:.2f} MPa ±{p['error_pct']:.1f} % at crank {p['crank_deg']:.1f}° "
                              f"on {_e(p['surface'])}, ({', '.join(f'{c:.2f}' for c in p['location_mm'])}) mm"),
                     ("verdict", f"{_badge(p['verdict'])} {p['utilisation_pct']:.1f} % of {p['limit_mpa']:.0f} MPa"),
                     ("largest displacement", f"{p['max_displacement_mm']:.3g} mm"),
                     ("mesh", f"{p['mesh']['nodes']} nodes, {p['mesh']['tets']} tetrahedra, {p['mesh']['dofs']} "
                              f"DOF (P{p['mesh']['order']}), quality min {p['mesh']['quality_min']:.2f}, "
                              f"{p['mesh']['straightened']} curved elements straightened"),
                     ("solve", f"{_e(p['solve']['method'])}, {p['solve']['load_cases']} load cases, "
                               f"{p['solve']['rows']} crank angles, residual ≤ {p['solve']['residual_max']:.1e}")]
            fat = p.get("fatigue")
            if fat:
                items.append(("Goodman fatigue", f"{_badge(fat['verdict'])} safety factor {fat['safety_factor']:.2f} "
                                                 f"(mean {fat['mean_mpa']:.1f} MPa, alternating "
                                                 f"{fat['alternating_mpa']:.1f} MPa, Se {fat['se_mpa']:.0f} MPa)"))
            items += [("note", _e(n)) for n in p.get("notes", [])]
            out += [f"<h4>{_e(p['mode'])} mode</h4>", _kv(items)]
    if r.get("differences"):
        out += ["<h2>Original vs cycle mode</h2>", "<ul>"] + [f"<li>{_e(d)}</li>" for d in r["differences"]] + ["</ul>"]
    # files
    vtk = r.get("field_files", [])
    out += ["<h2>Files</h2>",
            "<p>Open a <code>.vtu</code> (the critical crank angle) or a <code>.pvd</code> (the animation over the "
            "crank cycle) in ParaView (File → Open); colour by <code>von_mises</code> or "
            "<code>safety_factor</code>, and apply <i>Warp By Vector</i> on <code>displacement</code> to see "
            "the deformed part.</p><ul>"]
    out += [f"<li><code>{_e(f)}</code></li>" for f in vtk]  # written by the run, not kept in the repository
    out += ["</ul>", f'<p class="note">Also: {_e(", ".join(f for f in r.get("files", []) if f not in vtk))}</p>',
            "</body></html>"]
    return "\n".join(x for x in out if x)


def write_html(report: dict, folder: str | Path) -> Path:
    """Write ``report.html`` into the result folder (pictures already there)."""
    path = Path(folder) / "report.html"
    path.write_text(render_html(report, folder), encoding="utf-8")
    return path
