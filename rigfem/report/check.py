"""The report stage of a check: the report dict of what it found, and its result folder written at once.

The folder holds ``report.json`` (the dict), ``report.md`` and ``report.html`` beside one VTU per
part and mode (the critical crank angle), a ParaView ``.pvd`` animation per part over the crank
cycle (cycle mode) with the 3-D view's markers (``<part>_cycle_markers.json``: supports, pin loads per
frame), and PNG pictures.  It appears only when everything is written
(:func:`rigfem.report.folder.atomic_dir`).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from rigfem import __version__
from rigfem.report.provenance import provenance
from rigfem.context import Context
from rigfem.fe.partcase import CaseResult, supports_of
from rigfem.io.calculix import export_model
from rigfem.job import Checked
from rigfem.report.document import (ASSUMPTIONS, REPORT_SCHEMA, UNITS, finite, material_table, render_markdown,
                                    write_json)
from rigfem.report.figures import allowable_label, conclusion, part_label, part_minima, safety_factor
from rigfem.report.entries import part_entry
from rigfem.report.folder import Output, atomic_dir
from rigfem.report.html import write_html
from rigfem.report.picture_cache import (  # drawn once, then copied from the cache
    plot_peaks,
    reactions_plot,
    started_part_pictures,
    utilisation_plot,
    write_frames,
    write_vtu,
)
from rigfem.report.vtu import write_frame

__all__ = ["document", "write_check"]


_WHY = {"crank_rail": ("the crank really bends: the motor torque enters at its pivot coupling and is "
                       "reacted by the transverse pin force at A; original mode adds the load factor and "
                       "puts that force at the far end of the rail, held at its pivot"),
        "rail": ("a pin-jointed bar carries its joint forces almost only along its axis (a two-force "
                 "member but for its own inertia); the study's cantilever model — rail held at its pivot, "
                 "load factor × the peak force at the far end — turns the force's transverse component "
                 "into bending over the whole rail, which the real bar never sees"),
        "plate": "both modes load the bearing seat; original mode multiplies the peak by the load factor",
        "post": ("original mode applies the study's fixed 250 N + 250 N per screw; cycle mode the "
                 "actual pin force through the top screws")}


def _differences(parts: list[dict]) -> list[str]:
    """Where original and cycle mode differ, part by part, and why."""
    out = []
    by = {(p["name"], p["mode"]): p for p in parts}
    for (name, mode), p in by.items():
        if mode != "original" or (name, "cycle") not in by:
            continue
        c = by[(name, "cycle")]
        kind = (name if name in _WHY else "rail" if "rail" in name else
                "plate" if name.startswith("plate") else "post")
        ratio = c["peak_mpa"] / p["peak_mpa"] if p["peak_mpa"] > 0 else 0.0
        out.append(f"{name}: original {p['peak_mpa']:.1f} MPa at {p['surface']}, cycle "
                   f"{c['peak_mpa']:.1f} MPa at {c['surface']} (crank {c['crank_deg']:.0f}°), cycle/original "
                   f"= {ratio:.2f}: {_WHY[kind]}")
    return out


def _parts(checked: Checked) -> list[dict]:
    """The report entry of every part case (a linkage at a toggle: every part fails, unsolved)."""
    s, singular = checked.job.settings, checked.reactions.singular
    if singular:
        return [{"name": p, "part": spec["part"], "mode": m, "verdict": "fail", "peak_mpa": None,
                 "notes": [f"toggle (singular) crank-angle ranges {singular}: reactions grow "
                           f"without bound; no stress can be computed"]}
                for p, spec in s.parts.items() for m in s.modes]
    return [part_entry(r, pv, s) for r, pv in zip(checked.results, checked.verdicts.parts)]


def document(checked: Checked) -> dict:
    """The report dict of a check (plain data: MPa, mm, deg, N, N·m): what was checked, how, and
    what each part case gave; ``report.json`` is this dict."""
    job, sm, v = checked.job, checked.reactions.summary, checked.verdicts
    s, h = job.settings, checked.reactions.history
    parts = _parts(checked)
    for p in parts:
        p["safety_factor"] = safety_factor(p.get("peak_mpa"), v.limit_mpa)
        p["safety_factor_ultimate"] = safety_factor(p.get("peak_mpa"), s.material.sigma_u)
    return {
        "schema": REPORT_SCHEMA, "scene": job.scene.name, "description": job.description,
        "rigfem_version": __version__, "provenance": provenance(job.scene_sha256, job.input_sha256, job.author),
        "rule_violations": list(job.rule_violations), "assumed": h.meta.get("assumed", []),
        "verdict": v.overall, "stress_verdict": v.stress, "standing": v.standing, "left_out": v.left_out,
        "checked": v.checked,
        "not_checked": {"parts": list(v.not_checked[0]), "modes": list(v.not_checked[1])}, "limit_mpa": v.limit_mpa,
        "conclusion": conclusion(parts, v.limit_mpa, s.material.sigma_u), "part_minima": part_minima(parts),
        "units": [{"quantity": q, "unit": u} for q, u in UNITS], "assumptions": list(ASSUMPTIONS),
        "configuration": {"type": h.meta["type"], "lengths_mm": h.meta["lengths_mm"],
                          "speed_hz": job.scene.speed_hz, "model": h.meta["model"],
                          "samples": int(h.crank_deg.size), "branch": job.linkage.meta.get("branch", "open")},
        **{k: sm[k] for k in ("rules", "transmission_angle_deg", "peaks", "singular", "warnings")},
        "torque_Nm": sm.get("torque_Nm") or sm.get("driver_force_N"),
        "settings": {"modes": list(s.modes), "fidelity": s.fidelity, "order": s.order, "size_mm": s.size_mm,
                     "local_size_mm": s.local_size_mm, "adaptive": s.adaptive, "target_pct": s.target_pct,
                     "target_pct_of_peak": s.target_peak_pct,
                     "bearing_directions": s.bearing_directions,
                     "material": s.material.name, "sigma_u_mpa": s.material.sigma_u,
                     "load_factor": s.load_factor, "limit_factor": s.limit_factor, "fatigue": s.fatigue},
        "material": material_table(s.material),
        "parts": parts, "differences": _differences([p for p in parts if p.get("peak_mpa") is not None]),
    }


def _frames(d: Path, r: CaseResult, limit: float, cache) -> list[str]:
    """Write a cycle case's animation frames, their ParaView collection and its markers (:func:`_markers`);
    the collection's and the markers' names (none without frames)."""
    rows = sorted(r.frames)
    if not rows:
        return []
    fm = r.solution.model.mesh
    names = [f"{r.case.name}_{r.mode}_{k:03d}.vtu" for k in range(len(rows))]

    def write(folder: Path) -> None:
        for name, i in zip(names, rows):
            write_frame(folder / name, fm.nodes[:fm.n_vertices], fm.elements[:, :4], r.frames[i], limit)

    write_frames(d, names, r.solution, r.coef[rows], limit, write, cache)
    pvd = "\n".join(f'    <DataSet timestep="{float(r.case.rows[i]):g}" file="{f}"/>' for i, f in zip(rows, names))
    stem = f"{r.case.name}_{r.mode}"
    (d / f"{stem}.pvd").write_text('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
                                   f"  <Collection>\n{pvd}\n  </Collection>\n</VTKFile>\n")
    (d / f"{stem}_markers.json").write_text(json.dumps(finite(_markers(r, rows))))
    return [f"{stem}.pvd", f"{stem}_markers.json"]


def _markers(r: CaseResult, rows: list[int]) -> dict:
    """What the 3-D view draws on an animation besides the field: each support (its kind and the
    vertices of its surface), whether the part is a free body, and per frame the pin load on each
    loaded hole (its centre, mm, and force, N, in the part frame)."""
    fm = r.solution.model.mesh
    supports = [{"name": g, "kind": kind,
                 "vertices": [int(v) for v in np.unique(fm.surfaces[g]) if v < fm.n_vertices]}
                for kind, groups in r.case.supports for g in groups if g in fm.surfaces]
    frames = [{"crank_deg": float(r.case.rows[i]),
               "loads": [{"hole": g, "at_mm": [float(v) for v in at], "force_N": [float(v) for v in f]}
                         for g, at, f in r.frame_loads.get(i, [])]} for i in rows]
    return {"free_body": any(kind == "free" for kind, _ in r.case.supports), "supports": supports, "frames": frames}


def _outputs(d: Path, checked: Checked, parts: list[dict], output: Output, ctx: Context) -> tuple[list, list]:
    """Pictures (none without ``output.pictures``) of the reactions and of every part case, and field
    files (VTU/PVD/INP: ParaView/CalculiX, not kept in the repository's result folders); the
    pictures' scales go into ``parts``."""
    results, limit = checked.results, checked.verdicts.limit_mpa
    allowable = allowable_label(checked.job.settings.limit_factor, limit)
    fields, first, cache = [], [], ctx.cache
    worst: dict[str, CaseResult] = {}
    for r in results:  # one set of pictures per part: its mode with the highest peak
        if r.case.name not in worst or r.peak.value > worst[r.case.name].peak.value:
            worst[r.case.name] = r
    drawn = [(r, entry) for r, entry in zip(results, parts) if output.pictures and worst[r.case.name] is r]
    # and the part's other mode at its own critical crank angle (the cycle mode's governing angle): its
    # von Mises picture, same scale, same code, beside the full set's
    other = [(r, entry) for r, entry in zip(results, parts) if output.pictures and worst[r.case.name] is not r]
    of = {id(r): [] for r in results}  # each case's picture files, in the report's order
    jobs = [(r, r.coef[r.row], entry, limit, part_label(entry["name"], entry["part"]), allowable, d)
            for r, entry in drawn]
    jobs += [(r, r.coef[r.row], entry, limit, part_label(entry["name"], entry["part"]), allowable, d, 30.0,
              ("von_mises",), f"{r.case.name}_{r.mode}_mode") for r, entry in other]
    with started_part_pictures(jobs, cache) as wait:  # drawn in child processes while this one writes files
        ctx.observer.stage("report: reactions and peaks pictures, field files")
        if output.pictures:
            reactions_plot(checked.reactions.history, d / "reactions.png", cache)
            first.append("reactions.png")
        if output.pictures and results:
            plot_peaks(list(results), limit, d / "peak_von_mises.png", allowable, cache)
            first.append("peak_von_mises.png")
        for r, entry in zip(results, parts):
            stem, c = f"{r.case.name}_{r.mode}", r.coef[r.row]
            write_vtu(d / f"{stem}.vtu", r.solution, c, allowable=limit, cache=cache)
            fields.append(f"{stem}.vtu")
            if output.export_inp:  # written last (write_check), once the report is
                fields.append(f"{stem}.inp")
            if output.pictures and r.mode == "cycle":
                utilisation_plot(r, limit, d / f"{r.case.name}_utilisation.png",
                                 part_label(entry["name"], entry["part"]), allowable, cache)
                of[id(r)].append(f"{r.case.name}_utilisation.png")
            animation = _frames(d, r, limit, cache)
            if animation:
                fields += [f"{stem}_{k:03d}.vtu" for k in range(len(r.frames))] + animation
        ctx.observer.stage("report: the parts' pictures")
        for (r, entry), pics in zip(drawn + other, wait()):
            entry["pictures"] = pics
            of[id(r)][:0] = list(pics["files"].values())
    return first + [f for r in results for f in of[id(r)]], fields


def write_check(checked: Checked, report: dict, output: Output, ctx: Context) -> dict:
    """Write the result folder of a check (``output``; the pictures' scales and the file lists go
    into ``report``, which is returned); the folder appears only when everything is written."""
    report = dict(report)
    if not output.pictures:
        report["pictures"] = "not made (rigfem check --no-pictures)"
    ctx.observer.stage("report")
    with atomic_dir(output.path, output.force) as d:
        parts = [dict(p) for p in report["parts"]]
        pics, fields = _outputs(d, checked, parts, output, ctx)
        report = {**report, "parts": parts}
        report["files"] = ["report.json", "report.md", *pics, "report.html"]
        report["field_files"] = fields
        ctx.observer.stage("report: report.json, report.md, report.html")
        write_json(report, d / "report.json")
        (d / "report.md").write_text(render_markdown(report), encoding="utf-8")
        write_html(report, d, ctx.cache)
        if output.export_inp:
            _export(d, checked.results)
    return report


def _export(d: Path, results: tuple[CaseResult, ...]) -> None:
    """Each part case's identical model at its critical crank angle, as a CalculiX deck."""
    for r in results:
        export_model(r.solution.model, supports_of(r.case), r.solution.loads(r.coef[r.row])[:, None],
                     d / f"{r.case.name}_{r.mode}.inp",
                     heading=f"rigfem {r.case.name} {r.mode} crank {r.crank_deg:.2f} deg")
