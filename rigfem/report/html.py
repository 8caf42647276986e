"""``report.html``: the check report as one self-contained page (pictures embedded, 3-D view inline).

Built from the report dict and the files of the result folder only (template
``rigfem/templates/report.html.j2``), so the page carries exactly the numbers of ``report.json``
and every section of ``report.md`` (the same Markdown sections, rendered).  The template
autoescapes: every text that can come from a user's file (scene description, names, notes)
shows as text.  Opens in any browser without a server, offline; it is the one file to hand in,
and prints (a print stylesheet: A4, a page per part) to the PDF of ``rigfem show --pdf``.
"""

from __future__ import annotations

import base64
import io
from pathlib import Path

from rigfem.cache import Cache, resolve
from rigfem.files import file_sha256
from rigfem.report.document import (MODE_TEXT, assumption_lines, configuration_lines, loads_lines, model_lines,
                                    study_tables, title_block)
from rigfem.report.figures import allowable_label, asked_text, band, by_utilisation, safety_factor, stopped_text
from rigfem.report.pages import json_script, markdown_html, render_page
from rigfem.report.viewer import viewer_data
from rigfem.settings import MODES

__all__ = ["EMBED_HALVED_PX", "embedded_png", "render_html", "write_html"]

#: a picture at least this wide is embedded at half its size (a part's 1600 px field picture: the
#: page's width; the full-size file stays in the folder)
EMBED_HALVED_PX = 1600
#: WebP quality of an embedded picture (90: text and thin lines stay sharp)
EMBED_QUALITY = 90


def embedded_png(path: Path, cache: Cache | None = None) -> str | None:
    """A PNG of the folder as a data URI, WebP-encoded (quality :data:`EMBED_QUALITY`: a quarter of
    the PNG's bytes, which keeps the self-contained page small) and halved when it is
    :data:`EMBED_HALVED_PX` wide or wider; None when it is absent.  The full-size PNG stays in the
    folder.  The encoding costs a tenth of a second a picture: ``cache`` keeps it by the PNG's bytes."""
    if not path.is_file():
        return None
    from importlib.metadata import version

    def encode() -> bytes:
        from PIL import Image

        with Image.open(path) as im:
            im = im.reduce(2) if im.width >= EMBED_HALVED_PX else im
            buf = io.BytesIO()
            im.save(buf, "WEBP", quality=EMBED_QUALITY, method=4)
        return buf.getvalue()

    inputs = {"kind": "embedded", "png": file_sha256(path), "quality": EMBED_QUALITY,
              "halved_px": EMBED_HALVED_PX, "pillow": version("pillow")}
    webp, _ = resolve(cache).cached("pictures", inputs, encode, lambda b, d: (d / "embedded.webp").write_bytes(b),
                                    lambda entry: bytes(entry.bytes("embedded.webp")))
    return "data:image/webp;base64," + base64.b64encode(webp).decode("ascii")


def render_html(report: dict, folder: str | Path, cache: Cache | None = None) -> str:
    """The HTML page of a check report whose pictures and animation frames lie in ``folder``."""
    folder = Path(folder)
    r = report
    names = list(dict.fromkeys(p["name"] for p in r["parts"]))
    pictures = {f: embedded_png(folder / f, cache) for f in ["reactions.png", "peak_von_mises.png"]
                + [f"{n}{s}.png" for n in names for s in ("", "_utilisation", "_displacement", "_safety_factor",
                                                          *(f"_{m}_mode" for m in MODES))]}
    # links only to the files kept with the report; the field files (VTU/PVD/INP, not kept in the
    # repository's result folders) are named, never linked
    kept = [f for f in r.get("files", []) if (folder / f).is_file() and f != "report.html"]
    fields = list(r.get("field_files", []))
    present = [f for f in fields if (folder / f).is_file()]
    viewer = viewer_data(folder, present, r["limit_mpa"], cache)
    return render_page(
        "report.html.j2", r=r, cfg=r["configuration"], s=r["settings"], torque=r.get("torque_Nm"),
        pictures=pictures, mode_text=MODE_TEXT, kept=kept, modes=MODES,
        fields=[f for f in fields if not f[:-4].rsplit("_", 1)[-1].isdigit()],
        parts_by_name={n: [p for p in r["parts"] if p["name"] == n] for n in names},
        viewer=[v["name"] for v in viewer], viewer_json=json_script(viewer),
        allowable=allowable_label(r["settings"]["limit_factor"], r["limit_mpa"]),
        standing=r["standing"], stress=r["stress_verdict"],
        rows=by_utilisation(r["parts"]), band=band, stopped=stopped_text, asked=asked_text,
        safety=lambda p: p.get("safety_factor", safety_factor(p.get("peak_mpa"), r["limit_mpa"])),
        md={k: markdown_html("\n".join(f(r))) for k, f in
            (("title", title_block), ("configuration", configuration_lines), ("assumptions", assumption_lines),
             ("loads", loads_lines), ("tables", study_tables), ("model", model_lines))})


def write_html(report: dict, folder: str | Path, cache: Cache | None = None) -> Path:
    """Write ``report.html`` into the result folder (pictures already there)."""
    path = Path(folder) / "report.html"
    path.write_text(render_html(report, folder, cache), encoding="utf-8")
    return path
