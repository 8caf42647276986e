"""The check report as a document (issue 40 §1, issue 39 §3): a title block with the provenance,
the conclusion first, the verdicts sorted by utilisation with the governing case marked, the
factor of safety and what it is against, units, assumptions, loads and fixtures, what a check of
a subset left out; the HTML holds every section of the Markdown and is one file; the terminal's
summary says the same; ``rigfem compare``."""

import hashlib
import json
import re
import shutil
from html.parser import HTMLParser
from pathlib import Path

import pytest

from rigfem.cli import main
from rigfem.report.compare import compare
from rigfem.report.document import REPORT_SCHEMA, render_markdown
from rigfem.report.figures import by_utilisation

ROOT = Path(__file__).resolve().parents[1]
#: a check of a subset: plate_A and post_B (very different peaks), original mode only
SUBSET = ["--parts", "plate_A,post_B", "--modes", "original", "--fidelity", "draft", "--samples", "72",
          "--frames", "0", "--quiet"]


class _Page(HTMLParser):
    """The text, headings, links and images of a page."""

    def __init__(self, html: str):
        super().__init__()
        self.text, self.headings, self.links, self.images, self._h = [], [], [], [], None
        self.feed(html)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag in ("h1", "h2", "h3"):
            self._h = []
        if tag == "a" and a.get("href"):
            self.links.append(a["href"])
        if tag == "img":
            self.images.append(a)

    def handle_endtag(self, tag):
        if tag in ("h1", "h2", "h3") and self._h is not None:
            self.headings.append(" ".join("".join(self._h).split()))
            self._h = None

    def handle_data(self, data):
        self.text.append(data)
        if self._h is not None:
            self._h.append(data)


@pytest.fixture(scope="module")
def subset(tmp_path_factory):
    """``rigfem check`` of a subset with an author: its printed summary and its result folder."""
    out = tmp_path_factory.mktemp("doc") / "final-cm"
    capture = pytest.MonkeyPatch()
    import io
    import sys

    buf = io.StringIO()
    capture.setattr(sys, "stdout", buf)
    try:
        code = main(["check", "--out", str(out), "--author", "A. Student <lab 3>", *SUBSET])
    finally:
        capture.undo()
    assert code == 0
    return buf.getvalue(), out, json.loads((out / "report.json").read_text())


def test_a_subset_says_so_where_the_verdict_is_printed(subset):
    text, out, r = subset
    assert "overall: PASS (2 of 6 parts, original mode only)" in text
    assert r["checked"] == "2 of 6 parts, original mode only"
    assert r["not_checked"] == {"parts": ["crank_rail", "coupler_rail", "rocker_rail", "plate_B"], "modes": ["cycle"]}
    md = (out / "report.md").read_text()
    assert "**Overall verdict: PASS (2 of 6 parts, original mode only)**" in md
    assert "**not checked**: parts crank\\_rail, coupler\\_rail, rocker\\_rail, plate\\_B; cycle mode" in md
    page = " ".join(" ".join(_Page((out / "report.html").read_text()).text).split())
    assert "PASS (2 of 6 parts, original mode only)" in page
    assert "Not checked: parts crank_rail, coupler_rail, rocker_rail, plate_B; cycle mode" in page


def test_summary_names_the_governing_part_first_with_units_in_every_header(subset):
    text, _, r = subset
    lines = text.splitlines()
    gov = r["conclusion"]
    assert lines[1].startswith(f"governing: {gov['name']} ({gov['part']}), original mode: ")
    header = next(i for i, x in enumerate(lines) if x.startswith("part "))
    columns = re.split(r"\s{2,}|(?<=\)) ", lines[header].strip())
    unitless = [c for c in columns if "(" not in c and c not in ("part", "mode", "verdict", "where")]
    assert unitless == [], lines[header]
    rows = [x.split()[0] for x in lines[header + 1:header + 3]]
    assert rows == ["post_B", "plate_A"]  # by utilisation, the governing one first
    assert not re.search(r"\d\.\d{3,}", "\n".join(lines[header:])), "numbers rounded to what they mean"
    for row, part in zip(lines[header + 1:header + 3], ("post_B", "plate_A")):  # the mesh it reached, and why
        level = next(p for p in r["parts"] if p["name"] == part)["mesh"]["level"]
        assert re.search(rf"  {level} \(.+\)$", row), row
    assert any(x.startswith("mesh asked: ") and "% of the allowable" in x for x in lines), "what the check asked"


def test_title_block_carries_the_provenance(subset):
    _, out, r = subset
    pv = r["provenance"]
    assert r["schema"] == REPORT_SCHEMA == 7
    assert pv["rigfem_version"] == r["rigfem_version"] and pv["author"] == "A. Student <lab 3>"
    import rigfem

    if Path(rigfem.__file__).resolve().is_relative_to(ROOT):  # an editable install: rigfem runs from this checkout
        assert re.fullmatch(r"[0-9a-f]{40}", pv["commit"]) and pv["dirty"] in (True, False)
    else:  # a regular install (tests/run.sh, CI): the package is not a checkout
        assert pv["commit"] == "not a checkout"
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", pv["date_utc"])
    assert pv["python"] and pv["machine"]["cores"] > 0 and pv["machine"]["system"]
    assert set(pv["libraries"]) >= {"numpy", "scikit-fem", "gmsh", "pypardiso", "mkl"}
    assert all(pv["libraries"].values())
    scene = ROOT / "rigfem" / "scenes" / "final-cm.toml"
    assert pv["scene_sha256"] == hashlib.sha256(scene.read_bytes()).hexdigest()
    assert re.fullmatch(r"[0-9a-f]{64}", pv["input_sha256"])
    md, html = (out / "report.md").read_text(), (out / "report.html").read_text()
    for value in (pv["commit"], pv["date_utc"], pv["scene_sha256"], pv["input_sha256"], pv["libraries"]["gmsh"]):
        assert value.replace("-", "\\-").replace(".", "\\.") in md and value in html, value
    assert "A\\. Student &lt;lab 3\\>" in md and "A. Student &lt;lab 3&gt;" in html  # user text as text


def test_input_hash_follows_the_inputs_not_the_author(tmp_path):
    from rigfem.cache import from_environment
    from rigfem.job import Request, read_job

    cache = from_environment()
    a = read_job(Request("final-cm", {"fidelity": "draft"}, author="x"), cache)
    b = read_job(Request("final-cm", {"fidelity": "draft"}, author="y"), cache)
    c = read_job(Request("final-cm", {"fidelity": "standard"}), cache)
    assert a.input_sha256 == b.input_sha256 != c.input_sha256 and a.scene_sha256 == c.scene_sha256
    scene = tmp_path / "s.toml"
    scene.write_text((ROOT / "rigfem" / "scenes" / "final-cm.toml").read_text() + '\n[report]\nauthor = "T. A."\n')
    d = read_job(Request(scene), cache)
    assert d.author == "T. A." and d.scene_sha256 != a.scene_sha256


def test_conclusion_first_and_verdicts_sorted_with_the_governing_row_marked(subset):
    _, out, r = subset
    c = r["conclusion"]
    g = max(r["parts"], key=lambda p: p["utilisation_pct"])
    assert (c["name"], c["mode"]) == (g["name"], g["mode"])
    band = g["utilisation_pct"] * g["error_pct"] / 100
    assert c["utilisation_band_pct"] == pytest.approx([g["utilisation_pct"] - band, g["utilisation_pct"] + band])
    assert c["min_safety_factor"] == pytest.approx(r["limit_mpa"] / g["peak_mpa"])
    assert c["min_safety_factor_ultimate"] == pytest.approx(r["settings"]["sigma_u_mpa"] / g["peak_mpa"])
    assert c["reserve_pct"] == pytest.approx(100 - g["utilisation_pct"] - band)
    md = (out / "report.md").read_text()
    assert md.index("## Conclusion") < md.index("## Verdict per part case") < md.index("## Configuration")
    table = md[md.index("## Verdict per part case"):].split("\n\n")[2].splitlines()[2:]
    utils = [float(row.split("|")[5]) for row in table]
    assert utils == sorted(utils, reverse=True) and "▶ governing" in table[0]
    assert sum("governing" in row for row in table) == 1
    html = (out / "report.html").read_text()
    rows = re.findall(r"<tr( class=governing)?><td>(?:▶ governing)?</td><td>(\w+) <span", html)
    assert [n for _, n in rows] == [p["name"] for p in by_utilisation(r["parts"])] and rows[0][0]
    assert html.index("Governing:") < html.index("Verdict per part case") < html.index("Title block")


def test_factor_of_safety_says_against_what_and_per_part(subset):
    _, out, r = subset
    for p in r["parts"]:
        assert p["safety_factor"] == pytest.approx(r["limit_mpa"] / p["peak_mpa"])
        assert p["safety_factor_ultimate"] == pytest.approx(2 * p["safety_factor"])  # the allowable is σu/2
    assert [m["name"] for m in r["part_minima"]] == ["post_B", "plate_A"]
    md = (out / "report.md").read_text()
    assert "Factor of safety = allowable σu/2 / peak von Mises" in md
    assert "| part | against the allowable (–) | against σu (–) | in mode |" in md
    assert "factor of safety vs σu/2 (–)" in (out / "report.html").read_text()


def test_loads_and_fixtures_balance_per_part_case(subset):
    _, out, r = subset
    for p in r["parts"]:
        lf = p["loads"]
        assert lf["crank_deg"] == p["crank_deg"] and lf["loads"] and lf["fixtures"] and not lf["free_body"]
        applied = sum(sum(x["force_N"][i] for x in lf["loads"]) for i in range(3))
        held = sum(sum(x["reaction_N"][i] for x in lf["fixtures"]) for i in range(3))
        assert applied == pytest.approx(-held, rel=1e-3, abs=1e-3)
        assert all(x["magnitude_N"] >= 0 for x in lf["loads"] + lf["fixtures"])
    md = (out / "report.md").read_text()
    plate = next(p for p in r["parts"] if p["name"] == "plate_A")
    assert "| pin on the bearing seat | bearing load |" in md and "| screw\\_1 | fixture: screw" in md
    assert f"{plate['loads']['loads'][0]['magnitude_N']:.1f} |" in md


def test_free_body_is_said_to_be_free():
    """A cycle-mode rail's support reactions read (0, 0, 0): the report says it is a free body."""
    r = _report_with_free_body()
    md = render_markdown(r)
    assert "(0.0, 0.0, 0.0) (free body: no support)" in md
    assert "Free body: no support reactions" in md


def _report_with_free_body() -> dict:
    r = json.loads((ROOT / "results" / "final-cm" / "report.json").read_text())
    p = next(p for p in r["parts"] if p["mode"] == "cycle" and "rail" in p["name"])
    p["loads"] = {"crank_deg": p["crank_deg"], "free_body": True, "fixtures": [],
                  "loads": [{"entity": "screw in hole_00", "kind": "bearing load", "force_N": [1.0, 0.0, 0.0],
                             "magnitude_N": 1.0}]}
    p["balance"]["supports_N"] = [0.0, 0.0, 0.0]
    return r


def test_html_holds_every_section_of_the_markdown_and_is_one_file(subset):
    """Every section of report.md is in report.html; its pictures and notes in the HTML's per-part sections."""
    _, out, r = subset
    md = (out / "report.md").read_text()
    page = _Page((out / "report.html").read_text())
    sections = [re.sub(r"\\(.)", r"\1", h[3:]) for h in re.findall(r"^## .*$", md, flags=re.M)]
    assert {"Conclusion", "Units", "Assumptions and limitations", "Model", "Mesh per part"} <= set(sections)
    missing = [s for s in sections if s not in page.headings and s not in ("Pictures", "Notes per part case")]
    assert missing == [], missing
    assert sorted(re.findall(r"\]\(([^)]+\.png)\)", md)) == sorted(i["data-file"] for i in page.images
                                                                  if i["data-file"].startswith(("plate", "post")))
    text = " ".join(" ".join(page.text).split())
    assert all(" ".join(n.split()) in text for p in r["parts"] for n in p["notes"])
    assert page.images and all(i["src"].startswith("data:image/webp;base64,") for i in page.images)
    assert all((out / link).is_file() for link in page.links), page.links


def _links_to_missing_files(folder: Path) -> list[str]:
    """The links and pictures of a folder's report.html and report.md that are not files of the folder."""
    page = _Page((folder / "report.html").read_text(encoding="utf-8"))
    targets = [link for link in page.links if not link.startswith(("#", "http://", "https://"))]
    targets += [i["src"] for i in page.images if not i["src"].startswith("data:")]
    targets += re.findall(r"\]\(([^)#]+)\)", (folder / "report.md").read_text(encoding="utf-8"))
    return [t for t in targets if not (folder / t).is_file()]


def test_a_fresh_folder_as_committed_links_only_files_that_exist(subset, tmp_path):
    """The repository keeps a result folder without its VTU/PVD/INP files (.gitignore): its report,
    written before they were left out, must not link them."""
    _, out, r = subset
    folder = tmp_path / "committed"
    shutil.copytree(out, folder, ignore=shutil.ignore_patterns("*.vtu", "*.pvd", "*.inp", "*_markers.json"))
    assert r["field_files"] and not list(folder.glob("*.vtu"))
    assert _links_to_missing_files(folder) == []
    assert all(f in (folder / "report.html").read_text() for f in r["field_files"])  # named, not linked


def _committed_folders() -> list[Path]:
    return sorted(f.parent for f in (ROOT / "results").glob("*/report.html"))


@pytest.mark.parametrize("folder", _committed_folders(), ids=lambda f: f.name)
def test_a_committed_folder_links_only_files_that_exist(folder):
    """As committed, not rendered again: every link and picture of its report.html and report.md is
    a file of the folder (or embedded)."""
    assert _links_to_missing_files(folder) == []


def test_compare_lists_every_case_and_fails_when_a_verdict_got_worse(tmp_path, capsys):
    a = json.loads((ROOT / "results" / "final-cm" / "report.json").read_text())
    b = json.loads(json.dumps(a))
    b["parts"][0].update(verdict="fail", peak_mpa=400.0, utilisation_pct=400.0 / b["limit_mpa"] * 100)
    b["parts"][1].update(verdict="undecided")
    b["verdict"] = "fail"
    b["parts"] = [p for p in b["parts"] if p["name"] != "plate_B"]
    c = compare(a, b)
    rows = {(x["name"], x["mode"]): x for x in c["rows"]}
    first = a["parts"][0]
    assert rows[(first["name"], first["mode"])]["change"] == "worse"
    assert rows[(first["name"], first["mode"])]["peak_change_mpa"] == pytest.approx(400.0 - first["peak_mpa"])
    assert rows[("plate_B", "original")]["change"] == "only in A" and c["overall_change"] == "worse"
    assert len(c["worse"]) == 3  # two part cases and the overall verdict
    better = compare(b, a)
    assert better["worse"] == [] and better["overall_change"] == "better"
    for name, rep in (("a", a), ("b", b)):
        (tmp_path / name).mkdir()
        (tmp_path / name / "report.json").write_text(json.dumps(rep))
    assert main(["compare", str(tmp_path / "a"), str(tmp_path / "b"), "--out", str(tmp_path / "c")]) == 1
    out = capsys.readouterr().out
    assert "**Verdicts that got worse: " in out and "| **worse** |" in out
    assert main(["compare", str(tmp_path / "b"), str(tmp_path / "a")]) == 0
    page = _Page((tmp_path / "c" / "compare.html").read_text())
    assert "rigfem compare: a vs b" in page.headings and "|---" not in "".join(page.text)
    assert main(["compare", str(tmp_path / "a"), str(tmp_path)]) == 2  # a folder without report.json


def test_check_list_loads_nothing_of_the_fe():
    import subprocess
    import sys

    code = ("import sys; from rigfem.cli import main; main(['check', '--list']); "
            "print(sorted(m for m in ('numpy', 'scipy', 'skfem', 'rigfem.pipeline') if m in sys.modules))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and "final-cm" in r.stdout and r.stdout.strip().endswith("[]"), r.stdout[-300:]
    assert r.stderr == ""  # no progress line: nothing to wait for


def test_progress_counts_down_the_estimate_on_a_terminal_as_in_a_log():
    import io

    from rigfem.cli import progress

    for terminal in (True, False):
        stream = io.StringIO()
        with progress.heartbeat("check", stream, after_s=0.0, every_s=0.05, terminal=terminal):
            progress.OBSERVER.stage("solving part plate_A (coarse) · 2 of 6 cases done")
            progress.OBSERVER.remaining(120.0)
            import time

            time.sleep(1.3)
        text = stream.getvalue()
        assert "rigfem check: solving part plate_A (coarse) · 2 of 6 cases done · about 2 min left" in text
        assert re.search(r"left … \d+ s", text), text


def test_compare_two_scenes(tmp_path, capsys):
    """Scenes are checked first; nothing of those checks is kept."""
    import tempfile

    base = (ROOT / "rigfem" / "scenes" / "final-cm.toml").read_text().split("[check]")[0]
    check = '[check]\nparts = ["plate_A"]\nmodes = ["original"]\nfidelity = "draft"\nsamples = 72\n'
    (tmp_path / "slow.toml").write_text(base + check)
    (tmp_path / "fast.toml").write_text(base.replace("speed_hz = 1.0", "speed_hz = 2.0") + check)
    before = set(Path(tempfile.gettempdir()).glob("rigfem-compare-*"))
    assert main(["compare", str(tmp_path / "slow.toml"), str(tmp_path / "fast.toml"), "--json"]) == 0
    c = json.loads(capsys.readouterr().out)
    assert c["scenes"] == ["slow", "fast"] and [r["change"] for r in c["rows"]] == ["same"]
    assert c["rows"][0]["peak_change_mpa"] > 0  # twice the speed: larger inertia forces
    assert set(Path(tempfile.gettempdir()).glob("rigfem-compare-*")) == before


def test_dirty_means_the_code_that_ran_changed(tmp_path):
    """A changed result or page leaves a run clean; a changed or added package file makes it dirty."""
    import subprocess

    from rigfem.report.provenance import _commit

    def git(*a):
        subprocess.run(["git", "-C", str(tmp_path), *a], check=True, capture_output=True)

    (tmp_path / "rigfem").mkdir(), (tmp_path / "results").mkdir()
    for f in ("pyproject.toml", "rigfem/a.py", "results/r.md", "README.md"):
        (tmp_path / f).write_text("x\n")
    git("init", "-q"), git("add", "."), git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "c")
    assert _commit(tmp_path)[1] is False
    (tmp_path / "results/r.md").write_text("y\n"), (tmp_path / "README.md").write_text("y\n")
    (tmp_path / "results/new.json").write_text("{}\n")
    assert _commit(tmp_path)[1] is False
    (tmp_path / "rigfem/b.py").write_text("y\n")
    assert _commit(tmp_path)[1] is True
    (tmp_path / "rigfem/b.py").unlink(), (tmp_path / "pyproject.toml").write_text("y\n")
    assert _commit(tmp_path)[1] is True
    git("checkout", "pyproject.toml"), (tmp_path / "geometry").mkdir(), (tmp_path / "geometry/p.toml").write_text("")
    assert _commit(tmp_path)[1] is True


@pytest.mark.parametrize("scene", ["final-cm", "final-nc", "final-nm", "slider-crank-300-840"])
def test_no_negative_zero_in_a_committed_report(scene):
    """A value that rounds to zero prints 0.0: "-0.0" (a -1e-9 N reaction, a location a hair below 0) reads
    as a sign that means something."""
    for name in ("report.md", "report.html"):
        text = (ROOT / "results" / scene / name).read_text(encoding="utf-8")
        assert not re.findall(r"(?<![\d.])-0\.0*(?![0-9])", text), name
