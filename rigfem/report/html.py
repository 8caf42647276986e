"""``report.html``: the check report as one self-contained page (pictures embedded, 3-D view inline).

Built from the report dict and the files of the result folder only (template
``rigfem/templates/report.html.j2``), so the page carries exactly the numbers of ``report.json``.
The template autoescapes: every text that can come from a user's file (scene description, names,
notes) shows as text.  Opens in any browser without a server, offline.
"""

from __future__ import annotations

from pathlib import Path

from rigfem.cache import Cache
from rigfem.report.document import MODE_TEXT, allowable_label, study_tables
from rigfem.report.pages import json_script, markdown_html, render_page
from rigfem.report.viewer import viewer_data

__all__ = ["render_html", "write_html"]


def render_html(report: dict, folder: str | Path, cache: Cache | None = None) -> str:
    """The HTML page of a check report whose pictures and animation frames lie in ``folder``."""
    folder = Path(folder)
    r = report
    files = list(r.get("files", [])) + list(r.get("field_files", []))
    names = list(dict.fromkeys(p["name"] for p in r["parts"]))
    # pictures by relative name: they sit beside the page (embedding two dozen 1600 x 1000 PNGs made a
    # 12 MB page); the 3-D view's data stays embedded, so the folder works offline as it is
    pictures = {f: f if (folder / f).is_file() else None for f in ["reactions.png", "peak_von_mises.png"]
                + [f"{n}{s}.png" for n in names for s in ("", "_utilisation", "_displacement", "_safety_factor")]}
    # link only files that are in the folder (a committed report may come without its VTU files)
    present = [f for f in files if (folder / f).is_file() and f != "report.html"]
    vtk = [f for f in present if f.endswith((".vtu", ".pvd")) and not f[:-4].rsplit("_", 1)[-1].isdigit()]
    viewer = viewer_data(folder, present, r["limit_mpa"], cache)
    return render_page(
        "report.html.j2", r=r, cfg=r["configuration"], s=r["settings"], torque=r.get("torque_Nm"),
        pictures=pictures, mode_text=MODE_TEXT, vtk=vtk, others=[f for f in present if f not in vtk
                                                                and not f.endswith(".vtu")],
        parts_by_name={n: [p for p in r["parts"] if p["name"] == n] for n in names},
        viewer=[v["name"] for v in viewer], viewer_json=json_script(viewer),
        allowable=allowable_label(r["settings"]["limit_factor"], r["limit_mpa"]),
        tables=markdown_html("\n".join(study_tables(r))))


def write_html(report: dict, folder: str | Path, cache: Cache | None = None) -> Path:
    """Write ``report.html`` into the result folder (pictures already there)."""
    path = Path(folder) / "report.html"
    path.write_text(render_html(report, folder, cache), encoding="utf-8")
    return path
