"""The HTML pages in a real browser (headless Chromium, no server): no console error, no broken image
or link, no raw markup in the visible text, a screenshot that is not blank; the 3-D view and the
explorer respond.  A missing chromium fails these tests (CI installs it), it never skips them."""

import io
import re
import shutil
from pathlib import Path
from urllib.parse import unquote, urlparse

import matplotlib.image as mpimg
import pytest

from browser import Browser
from rigfem.pipeline import Output, Request, run_check
from rigfem.report.html import write_html

ROOT = Path(__file__).resolve().parents[1]
SWEEP = ROOT / "results" / "sweep"
RAW = ("|---", "`", "**", "True", "False", "{{", "{%")


@pytest.fixture(scope="module")
def browser():
    b = Browser()
    yield b
    b.close()


def _check_page(browser, path: Path, shots: Path):
    page = browser.open(path)
    assert page.errors() == [], path
    images = page.eval("[...document.images].map(i => [i.complete, i.naturalWidth, i.alt])")
    assert all(c and w > 0 for c, w, _ in images), images
    for href in page.eval("[...document.links].map(a => a.href)"):
        u = urlparse(href)
        assert u.scheme != "file" or Path(unquote(u.path)).exists(), href
    text = page.eval("document.body.innerText")
    assert not [m for m in RAW if m in text], [m for m in RAW if m in text]
    shot = page.screenshot(shots / (path.stem + ".png"))
    pix = mpimg.imread(io.BytesIO(shot.read_bytes()), format="png")
    assert pix.shape[0] > 500 and pix[..., :3].std() > 0.05, shot  # not blank
    return page


@pytest.mark.parametrize("name", ["sweep_four-bar.html", "sweep_slider-crank.html", "explorer.html"])
def test_sweep_pages(browser, name, tmp_path):
    _check_page(browser, SWEEP / name, tmp_path)


def test_explorer_responds(browser, tmp_path):
    page = _check_page(browser, SWEEP / "explorer.html", tmp_path)
    text = page.eval("document.getElementById('verdict').innerText")
    assert "Assembles" in text and "Meets the rig rules" in text and "Passes the stress criterion" in text
    assert "38.7 % of σu/2" in text and "crank_rail (original)" in page.eval("document.body.innerText")
    page.eval("(() => { const s = document.querySelector('select[data-l=d]'); s.value = '660';"
              " s.dispatchEvent(new Event('change')); })()")
    assert "Does not meet the rig rules" in page.eval("document.getElementById('verdict').innerText")
    assert "mount" not in page.eval("document.body.innerText").lower()
    assert page.errors() == []


def test_explorer_maps_have_labels_a_colour_bar_and_little_grey(browser, tmp_path):
    """Each map: both axes named with their unit (the y one turned upright), a colour bar in % of
    σu/2, and cropped to the cells with a number: the grey of "no number" is not most of it."""
    page = _check_page(browser, SWEEP / "explorer.html", tmp_path)
    drawn = page.eval("""(() => {
        const seen = [], fill = CanvasRenderingContext2D.prototype.fillText;
        CanvasRenderingContext2D.prototype.fillText = function (t, x, y) {
            if (this.canvas.parentNode && this.canvas.parentNode.id === 'maps') seen.push([String(t), this.getTransform().b]);
            return fill.apply(this, arguments); };
        const s = document.querySelector('select[data-l=b2]'); s.dispatchEvent(new Event('change'));
        CanvasRenderingContext2D.prototype.fillText = fill;
        return seen; })()""")
    upright = {t for t, b in drawn if b != 0}
    flat = {t for t, b in drawn if b == 0}
    assert {"d (mm)", "b4 (mm)"} <= flat and "b3 (mm)" in upright, drawn
    assert "peak utilisation (% of σu/2)" in upright and {"0", "100", "> 100"} <= flat
    grey = page.eval("""[...document.querySelectorAll('#maps canvas')].map((c) => {
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        let n = 0; for (let i = 0; i < d.length; i += 4) if (d[i] === 200 && d[i + 1] === 200 && d[i + 2] === 200) n++;
        return n / (c.width * c.height); })""")
    assert len(grey) == 2 and max(grey) < 0.45, grey  # 0.58-0.61 uncropped


COMMITTED = sorted(p.parent.name for p in (ROOT / "results").glob("*/report.html"))


@pytest.mark.heavy  # over 10 s: the default run stays under 10 minutes
@pytest.mark.parametrize("name", COMMITTED)
def test_committed_report_as_committed(browser, name, tmp_path):
    """The committed page itself (no field files beside it): it loads clean, its 3-D view (embedded)
    draws, and the same report.json renders again with today's code."""
    page = _check_page(browser, ROOT / "results" / name / "report.html", tmp_path)
    assert page.eval("document.getElementById('v-canvas') !== null"), "the committed page lost its 3-D view"
    drawn = page.eval("(() => { const c = document.getElementById('v-canvas'), d = c.getContext('2d')"
                      ".getImageData(0, 0, c.width, c.height).data; let n = 0;"
                      " for (let i = 0; i < d.length; i += 4) if (d[i] < 250 || d[i + 1] < 250 || d[i + 2] < 250) n++;"
                      " return n; })()")
    assert drawn > 1000, drawn  # pixels other than the view's white background: the part was drawn
    folder = tmp_path / name
    shutil.copytree(ROOT / "results" / name, folder)
    write_html(__import__("json").loads((folder / "report.json").read_text()), folder)
    _check_page(browser, folder / "report.html", tmp_path)


@pytest.mark.heavy
def test_committed_report_prints_to_pdf(tmp_path):
    from rigfem.cli import main

    assert main(["show", str(ROOT / "results" / "final-cm"), "--pdf", str(tmp_path / "r.pdf")]) == 0
    pdf = (tmp_path / "r.pdf").read_bytes()
    assert pdf.startswith(b"%PDF-") and pdf.rstrip().endswith(b"%%EOF")
    assert len(re.findall(rb"/Type\s*/Page\b", pdf)) >= 12  # a page per part case at least


@pytest.mark.heavy  # over 8 s: the default run stays under 10 minutes (CI's heavy stage runs it)
def test_report_3d_view(browser, tmp_path):
    out = tmp_path / "final-cm"
    run_check(Request("final-cm", {"fidelity": "draft", "parts": ["plate_A"], "frames": 3}), Output(out))
    page = _check_page(browser, out / "report.html", tmp_path)
    first = page.eval("document.getElementById('v-canvas').toDataURL()")
    text = page.eval("document.getElementById('v-angle').textContent")
    assert "governing" in text  # opens at the cycle's governing crank angle, not at 0°
    # the pin load's arrow (the pictures' colour) and the two screws' dark faces are drawn (issue 40 §2)
    counts = page.eval("(() => { const c = document.getElementById('v-canvas'), d = c.getContext('2d')"
                       ".getImageData(0, 0, c.width, c.height).data; let load = 0, held = 0;"
                       " for (let i = 0; i < d.length; i += 4) {"
                       "  if (Math.abs(d[i] - 216) < 4 && Math.abs(d[i + 1] - 27) < 4 && Math.abs(d[i + 2] - 96) < 4) load++;"
                       "  if (d[i] === d[i + 1] && d[i + 1] === d[i + 2] && d[i] > 20 && d[i] <= 48) held++; }"
                       " return [load, held]; })()")
    assert counts[0] > 200 and counts[1] > 50, counts
    n = int(page.eval("document.getElementById('v-frame').max")) + 1
    assert n in (3, 4)  # 3 even frames and the governing angle (unless it is one of them)
    page.eval("(() => { const s = document.getElementById('v-frame'); s.value = '0';"
              " s.dispatchEvent(new Event('input')); })()")
    assert page.eval("document.getElementById('v-angle').textContent").startswith("0.0°")
    page.eval(f"(() => {{ const s = document.getElementById('v-frame'); s.value = '{n - 1}';"
              " s.dispatchEvent(new Event('input')); })()")
    assert f"({n} of {n}" in page.eval("document.getElementById('v-angle').textContent")
    page.eval("document.getElementById('v-zin').click()")
    assert page.eval("document.getElementById('v-canvas').toDataURL()") != first
    assert page.errors() == []


@pytest.mark.heavy  # over 8 s: the default run stays under 10 minutes (CI's heavy stage runs it)
def test_fresh_report_first_screen_print_layout_and_pdf(browser, tmp_path):
    """A fresh folder: the conclusion and the governing row on the first screen; in print (A4) no
    table wider than the page, a page per part, the 3-D view left out; ``rigfem show --pdf`` renders."""
    from rigfem.cli import main

    out = tmp_path / "final-cm"
    run_check(Request("final-cm", {"fidelity": "draft", "parts": ["plate_A", "post_B"], "frames": 2}), Output(out))
    page = _check_page(browser, out / "report.html", tmp_path)
    first = page.eval("[document.querySelector('.conclusion').getBoundingClientRect().bottom,"
                      " document.querySelector('tr.governing').getBoundingClientRect().bottom]")
    assert max(first) < 1000, first  # both on the first screen of a 1400 x 1000 window
    assert "post_B" in page.eval("document.querySelector('tr.governing').innerText")
    page.b.call("Emulation.setEmulatedMedia", page.s, media="print")
    page.b.call("Emulation.setDeviceMetricsOverride", page.s, width=718, height=1000, deviceScaleFactor=1,
                mobile=False)  # A4's printable width at 10 mm margins, CSS px
    wide = page.eval("[...document.querySelectorAll('table')].map(t => t.getBoundingClientRect().right)"
                     ".filter(r => r > document.body.getBoundingClientRect().right + 1).length")
    assert wide == 0
    breaks = page.eval("[...document.querySelectorAll('section.part')].map(s => getComputedStyle(s).breakBefore)")
    assert breaks == ["auto", "page"] and page.eval("getComputedStyle(document.querySelector('h2.parts')).breakBefore") == "page"
    assert page.eval("getComputedStyle(document.querySelector('.interactive')).display") == "none"
    assert main(["show", str(out), "--pdf"]) == 0
    pdf = (out / "report.pdf").read_bytes()
    pages = len(re.findall(rb"/Type\s*/Page\b", pdf))
    assert pdf.startswith(b"%PDF-") and pdf.rstrip().endswith(b"%%EOF") and 4 <= pages <= 20, pages
