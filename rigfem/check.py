"""``rigfem check``: a scene → peak reactions → part load cases → FE → verdict → report folder.

>>> import pathlib, tempfile
>>> out = pathlib.Path(tempfile.mkdtemp()) / "final-cm"
>>> report = run_check("final-cm", out=out, quiet=True, overrides={
...     "parts": ["plate_A"], "modes": ["original"], "fidelity": "draft", "frames": 0})
>>> report["verdict"], [(p["name"], p["mode"]) for p in report["parts"]]
('pass', [('plate_A', 'original')])
>>> (out / "report.json").is_file()
True

The report dict is written as ``report.json`` and ``report.md`` beside one VTU per part and
mode (the critical crank angle), a ParaView ``.pvd`` animation per part over the crank cycle
(cycle mode), and PNG plots.  The folder appears only when everything is written.
"""

from __future__ import annotations

import dataclasses
import shutil
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rigfem import __version__
from rigfem.dynamics.cycle import cycle_history
from rigfem.dynamics.forces import loaded_linkage
from rigfem.dynamics.history import (
    JointHistory,
    ReactionHistory,
    peaks,
    spline_evaluator,
    summary,
)
from rigfem.dynamics.solver import reactions
from rigfem.errors import InputError, plain
from rigfem.fe.partcase import CaseResult, solve_cases, supports_of
from rigfem.io.calculix import export_model
from rigfem.io.reactions_csv import read_csv
from rigfem.linkage.mechanisms import crank_angles
from rigfem.linkage.model import Linkage, LinkageState
from rigfem.linkage.state import linkage_state
from rigfem.loads.cases import part_cases
from rigfem.material import table_material
from rigfem.report.document import (
    REPORT_SCHEMA,
    allowable_label,
    material_table,
    part_label,
    render_markdown,
    write_json,
)
from rigfem.report.folder import atomic_dir, check_writable, folder_lock
from rigfem.report.html import write_html
from rigfem.report.picture_cache import (  # drawn once, then copied from the cache
    plot_peaks,
    reactions_plot,
    started_part_pictures,
    utilisation_plot,
    write_vtu,
)
from rigfem.rig.rules import broken_rules
from rigfem.scene import Scene, load_scene, resolve
from rigfem.schema import validate_check
from rigfem.settings import REFERENCE_SCENE, CheckSettings, part_settings
from rigfem.verdict.criterion import allowable_stress, overall
from rigfem.verdict.part import settled, verdict_of


#: a reaction history whose joint forces (N) and driver load (N·m or N) all stay below this loads
#: nothing: the scene is refused rather than passed at 0 % (a rig's lightest crank carries ~15 N)
UNLOADED = 1e-6


#: [check] fields about the dynamics and outputs (the rest is rigfem.settings)
_DYNAMICS = {"samples": 360, "mass_model": "rigid-body", "frames": 12, "reactions_csv": None,
             "reactions_csv_missing": None}


@dataclass
class CheckScene:
    """A scene read for checking: linkage, check settings and dynamics options."""

    scene: Scene
    linkage: Linkage  #: the scene's linkage with the forces it names (rigfem.dynamics.forces)
    settings: CheckSettings
    description: str
    samples: int
    mass_model: str
    frames: int  #: VTU frames of the cycle animation (0: none)
    reactions_csv: Path | None  #: external reaction history replacing the dynamics' forces
    rule_violations: list[str] = dataclasses.field(default_factory=list)  #: broken rig rules (allowed explicitly)
    csv_missing: dict | None = None  #: values stated for columns the reactions CSV lacks
    crank_deg: np.ndarray | None = None  #: the crank angles of the turn (``samples`` of them)
    motion: LinkageState | None = None  #: the linkage's motion there (rigfem.linkage.state.linkage_state)


def load_check_scene(name: str | Path, overrides: dict | None = None,
                     allow_rule_violations: bool = False) -> CheckScene:
    """Read a scene file (or built-in name) with its ``[check]`` table; ``overrides`` win.

    The file and the merged ``[check]`` table are validated by :mod:`rigfem.schema` before
    anything is built; the reactions CSV (if any) must exist (it is read, and its coverage,
    sampling, units and columns checked, first thing in :func:`solve_scene`).  A rig scene that
    breaks a rig rule is refused (InputError naming the rule and its numbers) unless
    ``allow_rule_violations``; then the violations are kept for the report.  The stage descends:
    the linkage and its motion over the turn (handed to the dynamics as data), the parts, the
    rig rules, then the material.
    """
    path = resolve(name)
    sc = load_scene(path)
    data = sc.raw
    table = {**data.get("check", {}), **(overrides or {})}
    validate_check(table, path.name)
    dyn = {k: table.pop(k, v) for k, v in _DYNAMICS.items()}
    lk = loaded_linkage(sc)
    deg = crank_angles(int(dyn["samples"]))
    motion = linkage_state(lk, deg, sc.speed_hz)
    settings = part_settings(table, lk.meta["type"], lk.meta.get("rails_mm"))
    # a rig scene is built from the rig's catalogue; the textbook linkages (masses = "none") have no rig rules
    broken = broken_rules(lk.meta) if sc.raw.get("linkage", {}).get("masses", "rig") == "rig" else []
    if broken and not allow_rule_violations:
        raise InputError(f"scene {plain(path.name, 80)!r} breaks the rig rule {broken[0]}"
                         f"{f' (and {len(broken) - 1} more)' if len(broken) > 1 else ''}: it cannot be "
                         f"mounted as given; pass --allow-rule-violations to check it anyway")
    settings = dataclasses.replace(settings, material=table_material(table.get("material", "rig_steel")))
    desc = data.get("description", data["linkage"].get("title", ""))
    csv_path = None
    if dyn["reactions_csv"] is not None:
        csv_path = path.parent / str(dyn["reactions_csv"])
        if not csv_path.is_file():
            raise InputError(f"[check].reactions_csv = {plain(str(dyn['reactions_csv']), 80)!r}: no such file "
                             f"next to the scene ({plain(str(csv_path), 120)})")
    return CheckScene(sc, lk, settings, desc, int(dyn["samples"]), dyn["mass_model"], int(dyn["frames"]), csv_path,
                      broken, dyn["reactions_csv_missing"], deg, motion)


def imported_history(cs: CheckScene) -> ReactionHistory:
    """An external reaction history (CSV) on the scene's linkage.

    The CSV gives the joint forces and the driver torque; the linkage gives the joint
    positions and the bodies' motion at the CSV's crank angles (to place the loads on the
    parts and, in cycle mode, for the inertia loads).  Peaks are refined on a spline of the
    CSV.  A CSV whose forces do not balance the linkage's inertia shows up as the force and
    moment imbalance of each free part (above the tolerance the part is undecided).
    """
    ext = read_csv(cs.reactions_csv, cs.csv_missing)
    kin = reactions(cs.linkage, cs.motion.at(ext.crank_deg), ext.crank_deg, cs.scene.speed_hz)
    missing = [n for n in kin.joints if n not in ext.joints]
    if missing:
        raise InputError(f"reactions CSV {cs.reactions_csv.name} lacks joint(s) {', '.join(missing)}; "
                         f"the linkage has {', '.join(kin.joints)}")
    sign = {n: -1.0 if (ext.joints[n].body_a, ext.joints[n].body_b) == (j.body_b, j.body_a) else 1.0
            for n, j in kin.joints.items()}
    forces = spline_evaluator(ext)
    meta = dict(kin.meta, model=f"imported from {cs.reactions_csv.name}", singular=ext.meta["singular"],
                assumed=ext.meta["assumed"])

    def combine(f: ReactionHistory, k: ReactionHistory) -> ReactionHistory:
        joints = {n: JointHistory(n, j.body_a, j.body_b, sign[n] * f.joints[n].force_N, j.position_mm)
                  for n, j in k.joints.items()}
        return ReactionHistory(f.crank_deg, joints, f.torque_Nm, k.bodies, meta, evaluator=at,
                               full_turn=f.full_turn)

    def at(deg) -> ReactionHistory:
        d = np.atleast_1d(np.asarray(deg, float))
        order = np.argsort(d)  # the solver wants increasing angles; answer in the order asked
        k = kin.evaluator(d[order])  # the linkage's motion there, on the same branch
        back = np.argsort(order)
        for j in k.joints.values():
            j.position_mm = j.position_mm[back]
        k.bodies = {n: dataclasses.replace(b, angle_rad=b.angle_rad[back], omega_rad_s=b.omega_rad_s[back],
                                           alpha_rad_s2=b.alpha_rad_s2[back], origin_mm=b.origin_mm[back],
                                           origin_acc_mm_s2=b.origin_acc_mm_s2[back])
                    for n, b in k.bodies.items()}
        return combine(forces(d), k)

    return combine(ext, kin)


def _progress(total: int, quiet: bool):
    """A tqdm bar on stderr over the part cases (silent when quiet or not a terminal)."""
    from tqdm import tqdm

    bar = tqdm(total=total, unit="case", file=sys.stderr, disable=quiet or None,
               bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} [{elapsed}<{remaining}]")

    def step(name: str, mode: str) -> None:
        bar.set_description(f"{name} ({mode})")
        bar.update()
    return bar, step


def _differences(parts: list[dict]) -> list[str]:
    """Where original and cycle mode differ, part by part, and why."""
    why = {"crank_rail": ("the crank really bends: the motor torque enters at its pivot coupling and is "
                          "reacted by the transverse pin force at A; original mode adds the load factor and "
                          "puts that force at the far end of the rail, held at its pivot"),
           "rail": ("a pin-jointed bar carries its joint forces almost only along its axis (a two-force "
                    "member but for its own inertia); the study's cantilever model — rail held at its pivot, "
                    "load factor × the peak force at the far end — turns the force's transverse component "
                    "into bending over the whole rail, which the real bar never sees"),
           "plate": "both modes load the bearing seat; original mode multiplies the peak by the load factor",
           "post": ("original mode applies the study's fixed 250 N + 250 N per screw; cycle mode the "
                    "actual pin force through the top screws")}
    out = []
    by = {(p["name"], p["mode"]): p for p in parts}
    for (name, mode), p in by.items():
        if mode != "original" or (name, "cycle") not in by:
            continue
        c = by[(name, "cycle")]
        kind = (name if name in why else "rail" if "rail" in name else
                "plate" if name.startswith("plate") else "post")
        ratio = c["peak_mpa"] / p["peak_mpa"] if p["peak_mpa"] > 0 else 0.0
        out.append(f"{name}: original {p['peak_mpa']:.1f} MPa at {p['surface']}, cycle "
                   f"{c['peak_mpa']:.1f} MPa at {c['surface']} (crank {c['crank_deg']:.0f}°), cycle/original "
                   f"= {ratio:.2f}: {why[kind]}")
    return out


def _frames(r: CaseResult, frames: int) -> list[tuple[int, str]]:
    """(row, file name) of each frame of a cycle case's animation: ``frames`` crank angles, evenly spaced."""
    if r.mode != "cycle" or not frames:
        return []
    rows = np.unique(np.linspace(0, len(r.case.rows), frames, endpoint=False).astype(int))
    return [(int(i), f"{r.case.name}_{r.mode}_{k:03d}.vtu") for k, i in enumerate(rows)]


def _write_frames(r: CaseResult, frames: int, limit: float, folder: Path) -> list[int]:
    """Write a case's animation frames (compact VTU) into ``folder`` as soon as its part is final;
    the rows the report still needs of it: the critical one (:func:`rigfem.fe.partcase.solve_cases`
    then holds only that combination of the part's unit solutions)."""
    for i, name in _frames(r, frames):
        write_vtu(folder / name, r.solution, r.coef[i], allowable=limit, compact=True)
    return [r.row]


def _write_outputs(d: Path, h: ReactionHistory, results: list[CaseResult], parts: list[dict], limit: float,
                   allowable: str, frames: int, export_inp: bool, pictures: bool,
                   staged: Path) -> tuple[list[str], list[str]]:
    """Pictures (kept with the report; none without ``pictures``) of the reactions and of every
    part case, and field files (VTU/PVD/INP: ParaView/CalculiX, not kept in the repository's
    result folders; the animation frames moved from ``staged``, where :func:`_write_frames` put
    them); the pictures' scales go into ``parts``."""
    fields, first = [], []
    worst = {}
    for r in results:  # one set of pictures per part: its mode with the highest peak
        if r.case.name not in worst or r.peak.value > worst[r.case.name].peak.value:
            worst[r.case.name] = r
    drawn = [(r, entry) for r, entry in zip(results, parts) if pictures and worst[r.case.name] is r]
    of = {id(r): [] for r in results}  # each case's picture files, in the report's order
    jobs = [(r, r.coef[r.row], entry, limit, part_label(entry["name"], entry["part"]), allowable, d) for r, entry in drawn]
    with started_part_pictures(jobs) as wait:  # drawn in child processes while this one writes the field files
        if pictures:
            reactions_plot(h, d / "reactions.png")
            first.append("reactions.png")
        if pictures and results:
            plot_peaks(results, limit, d / "peak_von_mises.png", allowable)
            first.append("peak_von_mises.png")
        for r, entry in zip(results, parts):
            stem = f"{r.case.name}_{r.mode}"
            c = r.coef[r.row]
            write_vtu(d / f"{stem}.vtu", r.solution, c, allowable=limit)
            fields.append(f"{stem}.vtu")
            if export_inp:  # the identical model at the critical crank angle, for CalculiX
                export_model(r.solution.model, supports_of(r.case), r.solution.loads(c)[:, None], d / f"{stem}.inp",
                             heading=f"rigfem {r.case.name} {r.mode} crank {r.case.rows[r.row]:.2f} deg")
                fields.append(f"{stem}.inp")
            if pictures and r.mode == "cycle":
                utilisation_plot(r, limit, d / f"{r.case.name}_utilisation.png",
                                 part_label(entry["name"], entry["part"]), allowable)
                of[id(r)].append(f"{r.case.name}_utilisation.png")
            if r.mode == "cycle" and frames:
                series = []
                for i, name in _frames(r, frames):
                    shutil.move(staged / name, d / name)
                    series.append((float(r.case.rows[i]), name))
                pvd = "\n".join(f'    <DataSet timestep="{t:g}" file="{f}"/>' for t, f in series)
                (d / f"{stem}.pvd").write_text(
                    '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n'
                    f"{pvd}\n  </Collection>\n</VTKFile>\n")
                fields.append(f"{stem}.pvd")
        for (r, entry), pics in zip(drawn, wait()):
            entry["pictures"] = pics
            of[id(r)][:0] = list(pics["files"].values())
    return first + [f for r in results for f in of[id(r)]], fields


def solve_scene(cs: CheckScene, solver: str = "auto", quiet: bool = True, on_stage=None, on_final=None
                ) -> tuple[ReactionHistory, list[CaseResult], dict]:
    """The scene's reaction history (its dynamics, or an imported CSV), its summary (peaks,
    rules: :func:`rigfem.dynamics.history.summary`) and every part case solved; no cases at a
    toggle, where the reactions are unbounded.  ``on_stage(text)`` hears each stage as it
    begins (dynamics, meshing part X, solving part X).  Each case's solution holds its critical
    row's combination only, or the rows ``on_final(result)`` returns as its part is final (None:
    every unit solution; :func:`rigfem.fe.partcase.solve_cases`)."""
    if on_stage:
        on_stage("reactions from the CSV" if cs.reactions_csv else "dynamics")
    h = (imported_history(cs) if cs.reactions_csv else
         cycle_history(cs.linkage, cs.motion, cs.crank_deg, cs.scene.speed_hz, cs.mass_model))
    pk = peaks(h)
    digest = summary(h, pk)
    if h.meta.get("singular"):
        return h, [], digest
    force = max(float(np.abs(j.force_N).max()) for j in h.joints.values())
    torque = float(np.abs(h.torque_Nm).max())
    cases = part_cases(h, pk, cs.settings)
    if max(force, torque) < UNLOADED or not any(np.any(case.coef) for _, case in cases):
        raise InputError(f"scene {plain(cs.scene.name, 80)!r}: nothing loads its parts (largest joint force "
                         f"{force:.3g} N, driver {torque:.3g}: no masses or a massless linkage), so a stress "
                         f"check would pass at 0 %; for its motion alone use rigfem kinematics")
    bar, step = _progress(len(cases), quiet)
    with bar:
        return h, solve_cases(cases, cs.settings, solver=solver, progress=step, on_stage=on_stage,
                              settled=lambda r, shrink=1.0: settled(r, cs.settings, shrink),
                              on_final=on_final or (lambda r: [r.row])), digest


def run_check(name: str | Path = REFERENCE_SCENE, out: str | Path | None = None, force: bool = False,
              overrides: dict | None = None, quiet: bool = False, solver: str = "auto",
              export_inp: bool = False, allow_rule_violations: bool = False, pictures: bool = True,
              on_verdict=None, on_stage=None) -> dict:
    """Check a scene; write the report folder ``out`` (default results/<scene>); return the report.

    ``export_inp`` also writes each part case's model at its critical crank angle as a
    CalculiX deck (``<part>_<mode>.inp``: same nodes, C3D10/C3D4 elements, supports, loads).
    Everything checkable is checked before the computation (scene, options, rig rules unless
    ``allow_rule_violations``, reactions CSV (its file; its content first thing in the dynamics
    stage), output folder); the folder is locked while the check runs (a second run on it is
    refused).  ``on_verdict(report)`` is called once the verdicts are decided, before the
    pictures and files are written; without ``pictures`` no PNG is rendered and the report says
    so.  ``on_stage(text)`` hears each stage as it begins.
    """
    cs = load_check_scene(name, overrides, allow_rule_violations)
    out = Path(out) if out is not None else Path("results") / cs.scene.name
    check_writable(out, force)
    with folder_lock(out):
        return _check(cs, out, force, quiet, solver, export_inp, pictures, on_verdict, on_stage)


def _check(cs: CheckScene, out: Path, force: bool, quiet: bool, solver: str, export_inp: bool,
           pictures: bool = True, on_verdict=None, on_stage=None) -> dict:
    s = cs.settings
    limit = allowable_stress(s.material.sigma_u, s.limit_factor)
    # a part's animation frames are written as soon as it is final, and its unit solutions dropped
    with tempfile.TemporaryDirectory(prefix="rigfem-frames-") as staged:
        h, results, reactions = solve_scene(cs, solver, quiet, on_stage,
                                            lambda r: _write_frames(r, cs.frames, limit, Path(staged)))
        return _report(cs, out, force, h, results, reactions, limit, export_inp, pictures, on_verdict, on_stage,
                       Path(staged))


def _report(cs: CheckScene, out: Path, force: bool, h: ReactionHistory, results: list[CaseResult],
            reactions: dict, limit: float, export_inp: bool, pictures: bool, on_verdict, on_stage,
            staged: Path) -> dict:
    """Verdicts, report and files of a solved scene, written into ``out`` at once."""
    s = cs.settings
    if h.meta.get("singular"):
        parts = [{"name": p, "part": spec["part"], "mode": m, "verdict": "fail", "peak_mpa": None,
                  "notes": [f"toggle (singular) crank-angle ranges {h.meta['singular']}: reactions grow "
                            f"without bound; no stress can be computed"]}
                 for p, spec in s.parts.items() for m in s.modes]
    else:
        parts = [verdict_of(r, s) for r in results]
    # a configuration that cannot be mounted never passes, whatever its stresses
    verdict = "fail" if cs.rule_violations else overall(parts)
    report = {
        "schema": REPORT_SCHEMA, "scene": cs.scene.name, "description": cs.description,
        "rigfem_version": __version__,
        "rule_violations": cs.rule_violations, "assumed": h.meta.get("assumed", []),
        "verdict": verdict, "limit_mpa": limit,
        "configuration": {"type": h.meta["type"], "lengths_mm": h.meta["lengths_mm"],
                          "speed_hz": cs.scene.speed_hz, "model": h.meta["model"],
                          "samples": int(h.crank_deg.size), "branch": cs.linkage.meta.get("branch", "open")},
        **{k: reactions[k] for k in ("rules", "transmission_angle_deg", "peaks", "singular", "warnings")},
        "torque_Nm": reactions.get("torque_Nm") or reactions.get("driver_force_N"),
        "settings": {"modes": list(s.modes), "fidelity": s.fidelity, "order": s.order, "size_mm": s.size_mm,
                     "local_size_mm": s.local_size_mm, "adaptive": s.adaptive, "target_pct": s.target_pct,
                     "bearing_directions": s.bearing_directions,
                     "material": s.material.name, "sigma_u_mpa": s.material.sigma_u,
                     "load_factor": s.load_factor, "limit_factor": s.limit_factor, "fatigue": s.fatigue},
        "material": material_table(s.material),
        "parts": parts, "differences": _differences([p for p in parts if p.get("peak_mpa") is not None]),
    }
    if not pictures:
        report["pictures"] = "not made (rigfem check --no-pictures)"
    if on_verdict is not None:
        on_verdict(report)
    allowable = allowable_label(s.limit_factor, limit)
    if on_stage:
        on_stage("report")
    with atomic_dir(out, force) as d:
        pics, fields = _write_outputs(d, h, results, parts, limit, allowable, cs.frames, export_inp, pictures,
                                      staged)
        report["files"] = ["report.json", "report.md", *pics, "report.html"]
        report["field_files"] = fields
        write_json(report, d / "report.json")
        (d / "report.md").write_text(render_markdown(report), encoding="utf-8")
        write_html(report, d)
    return report


def read_report(folder: str | Path) -> dict:
    """The report dict of a result folder (for pytest limits)."""
    import json

    return json.loads((Path(folder) / "report.json").read_text())
