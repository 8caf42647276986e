"""The HTML report: self-contained, every picture embedded and not blank, the numbers of
report.json, user text escaped; the pictures' size; ``rigfem show``."""

import base64
import io
import json
from html.parser import HTMLParser

import matplotlib.image as mpimg
import numpy as np
import pytest

from rigfem.pipeline import Output, Request, run_check
from rigfem.cli import main
from rigfem.report.html import render_html
from said import one_line


class _Page(HTMLParser):
    def __init__(self):
        super().__init__()
        self.images, self.links, self.text = [], [], []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.images.append(a)
        if tag == "a":
            self.links.append(a.get("href"))

    def handle_data(self, data):
        self.text.append(data)


@pytest.fixture(scope="module")
def checked(tmp_path_factory):
    out = tmp_path_factory.mktemp("html") / "final-cm"
    report = run_check(Request("final-cm", {"fidelity": "draft", "parts": ["plate_A"], "frames": 2}), Output(out))
    return report, out


def _png(data: bytes) -> np.ndarray:
    return mpimg.imread(io.BytesIO(data), format="png")


def _picture(data: bytes):
    """An embedded picture (WebP) as an RGB array in [0, 1]."""
    from PIL import Image

    with Image.open(io.BytesIO(data)) as im:
        return np.asarray(im.convert("RGB"), dtype=float) / 255.0


def test_html_shows_every_picture_and_carries_the_json_numbers(checked):
    report, out = checked
    assert json.loads((out / "report.json").read_text()) == json.loads(json.dumps(report))
    page = _Page()
    page.feed((out / "report.html").read_text())
    pngs = sorted(f for f in report["files"] if f.endswith(".png"))
    assert sorted(i["data-file"] for i in page.images) == pngs
    for img in page.images:  # each picture embedded (the page is one file to hand in), its file beside it
        assert img["src"].startswith("data:image/webp;base64,") and (out / img["data-file"]).is_file()
        pix = _picture(base64.b64decode(img["src"].split(",", 1)[1]))
        assert pix.shape[1] >= 550 and pix[..., :3].std() > 0.02, img["data-file"]  # not blank
    text = " ".join(page.text)
    for p in report["parts"]:
        assert f"{p['peak_mpa']:.1f}" in text and f"{p['utilisation_pct']:.1f} %" in text
        assert p["verdict"].upper() in text
    assert f"{report['limit_mpa']:.0f} MPa" in text
    assert page.links and all((out / link).is_file() for link in page.links)  # links only to files there


def test_field_picture_size_and_content(checked):
    report, out = checked
    pix = _png((out / "plate_A.png").read_bytes())
    assert pix.shape[:2] == (1000, 1600)
    assert pix[..., :3].std() > 0.05
    util = _png((out / "plate_A_utilisation.png").read_bytes())
    assert util[..., :3].std() > 0.02


def test_user_text_is_escaped(checked):
    report, out = checked
    evil = dict(report, description='<script>alert("x")</script> & <b>bold</b>',
                warnings=["<img src=x onerror=alert(1)>"])
    page = render_html(evil, out)
    assert "<script>alert" not in page and "<img src=x" not in page
    assert "&lt;script&gt;" in page and "&amp;" in page


def test_show(checked, capsys, tmp_path):
    _, out = checked
    assert main(["show", str(out), "--print"]) == 0
    assert capsys.readouterr().out.strip().endswith("report.html")
    assert main(["show", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "RESULT_FOLDER" in one_line(err)


def test_scene_text_shows_as_text_in_every_page(tmp_path):
    """A description with a script shows as text; the sweep's Markdown renders (no raw separators)."""
    from rigfem.report.pages import markdown_html, render_page

    page = render_page("sweep.html.j2", kind="<script>x</script>",
                       body=markdown_html("| a | b |\n|---|---|\n| `c` | **d** <script>e</script> |\n"),
                       maps=[], explorer="explorer.html")
    assert "<script>x" not in page and "<script>e" not in page and "&lt;script&gt;" in page
    assert "|---|" not in page and "<code>c</code>" in page and "<strong>d</strong>" in page


def test_markdown_escapes_raw_html_and_keeps_entities():
    """The project's Markdown writes ``&lt;`` for a less-than sign (rule tables: mu_max &lt; 145 deg)
    and ``\\|`` for a bar inside a table cell: both read as the character, while raw HTML, inline
    or as a block, shows as text."""
    from rigfem.report.pages import markdown_html

    html = markdown_html("mu &lt; 145 & <b>x</b>\n\n<div>y</div>\n\n| cmd | n |\n|---|---:|\n| `a \\| b` | 1 |\n")
    assert "mu &lt; 145 &amp; &lt;b&gt;x&lt;/b&gt;" in html and "&amp;lt;" not in html
    assert "&lt;div&gt;y&lt;/div&gt;" in html and "<div>" not in html
    assert "<code>a | b</code>" in html and 'style="text-align:right"' in html


def test_the_3d_view_opens_at_the_governing_crank_angle(checked):
    """Even frames (2 here: 0° and 180°) miss the cycle's governing angle; the animation holds it and
    the 3-D view opens there, its peak marked (issue 40 §2)."""
    import re

    from rigfem.report.viewer import viewer_data

    report, out = checked
    cyc = next(p for p in report["parts"] if p["mode"] == "cycle")
    pvd = (out / f"{cyc['name']}_cycle.pvd").read_text()
    angles = [float(t) for t in re.findall(r'timestep="([^"]+)"', pvd)]
    assert any(abs(a - cyc["crank_deg"]) < 1e-6 for a in angles), (angles, cyc["crank_deg"])
    (view,) = viewer_data(out, [f"{cyc['name']}_cycle.pvd"], report["limit_mpa"])
    assert abs(view["angles"][view["governing"]] - cyc["crank_deg"]) < 1e-6
    assert view["peak"][view["governing"]] == max(view["peak"])
    page = (out / "report.html").read_text()
    assert "slider.value = String(d.governing || 0)" in page and "peak ${" in page


def test_the_other_mode_is_pictured_at_its_critical_crank_angle(checked):
    """Issue 40 §2: the field pictures showed the original mode only.  The part's other mode (here the cycle
    mode, at its governing crank angle) gets its von Mises picture too: the same picture code and colour scale,
    beside the original mode's in report.md and report.html."""
    report, out = checked
    by_mode = {p["mode"]: p for p in report["parts"]}
    full, cycle = by_mode["original"]["pictures"], by_mode["cycle"]["pictures"]
    assert set(full["files"]) == {"von_mises", "displacement", "safety_factor"}
    assert cycle["files"] == {"von_mises": "plate_A_cycle_mode.png"}
    assert cycle["utilisation_scale_pct"] == full["utilisation_scale_pct"] == [0.0, 100.0]
    assert cycle["utilisation_scale_mpa"] == full["utilisation_scale_mpa"]
    pix, orig = _png((out / "plate_A_cycle_mode.png").read_bytes()), _png((out / "plate_A.png").read_bytes())
    assert pix.shape[:2] == (1000, 1600) and pix[..., :3].std() > 0.05 and not np.array_equal(pix, orig)
    md = (out / "report.md").read_text()
    crank = by_mode["cycle"]["crank_deg"]
    assert f"plate\\_A \\(PF\\_4b\\_006\\), cycle mode at crank {crank:.1f}°: von Mises as utilisation" \
           "](plate_A_cycle_mode.png)" in md
    html = (out / "report.html").read_text()
    assert html.index('data-file="plate_A.png"') < html.index('data-file="plate_A_cycle_mode.png"') \
        < html.index('data-file="plate_A_utilisation.png"')


def test_the_3d_view_carries_the_supports_and_the_pin_load_of_every_frame(checked):
    """Issue 40 §2: the 3-D view had no loads nor supports.  Its data holds, from the animation's markers
    file, the part's supports (each surface vertex's support) and per frame the pin load on each loaded hole:
    at the governing frame the same force as the report's loads table; the page draws them."""
    from rigfem.report.viewer import viewer_data

    report, out = checked
    cyc = next(p for p in report["parts"] if p["mode"] == "cycle")
    assert f"{cyc['name']}_cycle_markers.json" in report["field_files"]
    (view,) = viewer_data(out, [f"{cyc['name']}_cycle.pvd"], report["limit_mpa"])
    assert view["supports"] == ["screw_1 (bolt)", "screw_2 (bolt)"] and view["free_body"] is False
    held = np.frombuffer(base64.b64decode(view["held"]), np.uint8)
    assert held.size == view["vertices"] and {1, 2} <= set(held.tolist()) and (held == 0).mean() > 0.5
    assert len(view["loads"]) == len(view["angles"]) and all(len(f) == 1 for f in view["loads"])
    (load,) = view["loads"][view["governing"]]
    (pin,) = [ld for ld in cyc["loads"]["loads"] if ld["kind"] == "bearing load"]
    assert load["name"] == "bore" and np.allclose(load["force"], pin["force_N"], rtol=0.01, atol=0.01 * pin["magnitude_N"])
    page = (out / "report.html").read_text()
    assert "held: ${name}" in page and "${l.name}: ${f.toFixed(0)} N" in page


def test_a_view_without_its_markers_file_still_draws_the_field(checked, tmp_path):
    """An animation written before the markers were: the field, no supports, no loads."""
    import shutil

    from rigfem.report.viewer import viewer_data

    report, out = checked
    folder = tmp_path / "old"
    shutil.copytree(out, folder, ignore=shutil.ignore_patterns("*_markers.json"))
    (view,) = viewer_data(folder, ["plate_A_cycle.pvd"], report["limit_mpa"])
    assert view["held"] is None and view["supports"] == [] and view["loads"] == [[]] * len(view["angles"])
