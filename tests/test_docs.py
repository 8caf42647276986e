"""The documentation is code that runs.

- Docstring examples: every ``>>>`` in the package is executed.
- The site (mkdocs.yml, docs/) builds with warnings as errors (a broken link or anchor, a page
  missing from the nav, a generation error), and what it renders holds no raw Markdown.
- The generated references cover every subcommand and option (from the argument parsers) and every
  scene-file key (from the pydantic schema, each with its note).
- Every fenced Python block of README and docs/ runs and prints the ``text`` block shown after it;
  every TOML block is a valid scene.
"""

import doctest
import importlib
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tomllib

import pytest

import rigfem
from docs_pages import ROOT, Block, all_blocks, gen, sandbox_env

PKG = pathlib.Path(rigfem.__file__).parent
WITH_EXAMPLES = sorted(
    ".".join(("rigfem", *f.relative_to(PKG).with_suffix("").parts))
    for f in PKG.rglob("*.py") if ">>>" in f.read_text() and f.name != "__init__.py")
GEN = gen()


def test_examples_exist():
    assert len(WITH_EXAMPLES) >= 5


@pytest.mark.parametrize("name", WITH_EXAMPLES)
def test_docstring_examples(name):
    mod = importlib.import_module(name)
    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0


# ---------------------------------------------------------------------------------- the site
def build(root: pathlib.Path, site: pathlib.Path) -> subprocess.CompletedProcess:
    """``mkdocs build --strict`` of the project at ``root`` into ``site``."""
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(site)], cwd=root,
                          capture_output=True, text=True, timeout=600, env=env)


#: what a page that rendered wrongly shows: a list item or a fence left as text, a marker or an HTML comment
#: escaped into the page, bold markup not converted
RAW = re.compile(r"<p>(?:[^<]|<(?!/p>))*?(?:^|\n|\. )[*-] (?:<|\w)|```|&lt;!--|\*\*\w")


def raw_markup(html: str) -> list[str]:
    """Markdown a rendered page shows as text (outside code)."""
    body = re.sub(r"<pre.*?</pre>|<script.*?</script>", "", html, flags=re.S)
    body = re.sub(r"<code.*?</code>", "CODE", body, flags=re.S)  # text, so `* <code>x</code>` still reads as a bullet
    return [m.group(0)[-80:] for m in RAW.finditer(body)]


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> pathlib.Path:
    out = tmp_path_factory.mktemp("site")
    r = build(ROOT, out)
    assert r.returncode == 0, f"mkdocs build --strict failed:\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}"
    assert "WARNING" not in r.stderr, r.stderr
    return out


def test_site_builds_strict(site):
    for page in ("index.html", "reference/cli/index.html", "reference/scene/index.html", "reference/moved/index.html",
                 "examples/index.html", "examples/custom_part/index.html", "performance/index.html",
                 "verification/index.html", "results/final-cm/crank_rail.png", "results/final-cm/report.html"):
        assert (site / page).is_file(), f"the site lacks {page}"
    cli = (site / "reference/cli/index.html").read_text()
    assert "rigfem check" in cli and "--fidelity" in cli
    scene = (site / "reference/scene/index.html").read_text()
    assert re.search(r"<h2[^>]*>\[linkage\.bodies\.&lt;name&gt;\]", scene), "a heading lost its <name>"


def test_no_page_shows_raw_markup(site):
    bad = {str(p.relative_to(site)): raw_markup(p.read_text()) for p in site.rglob("*.html")
           if p.parent.name != "search"}
    assert not {k: v for k, v in bad.items() if v}


def test_raw_markup_is_caught():
    assert raw_markup("<p>`x` opens it.\n* <code>report.json</code>: the machine interface</p>")
    assert raw_markup("<p>a <!-- fig:x --> left</p>".replace("<!--", "&lt;!--"))
    assert not raw_markup("<ul><li><code>report.json</code>: the interface</li></ul><p>a - b</p>")


def test_a_broken_link_fails_the_build(tmp_path):
    """The strict build is not strict by luck: the same project with one broken link does not build."""
    for name in ("mkdocs.yml", "docs", "examples"):
        (shutil.copytree if (ROOT / name).is_dir() else shutil.copy)(ROOT / name, tmp_path / name)
    (tmp_path / "results").symlink_to(ROOT / "results")
    page = tmp_path / "docs" / "guide" / "cache.md"
    page.write_text(page.read_text() + "\nSee [the cache's twin](no-such-page.md).\n")
    r = build(tmp_path, tmp_path / "site")
    assert r.returncode != 0 and "no-such-page.md" in r.stdout + r.stderr


# ---------------------------------------------------------------------------- generated references
def test_cli_reference_has_every_command_and_option():
    page = GEN.cli_reference()
    for name, parser in GEN.subparsers().items():
        assert f"## rigfem {name}" in page
        for action in parser._actions:
            for opt in action.option_strings:
                if opt not in ("-h", "--help"):
                    assert f"`{opt}" in page or f" {opt}`" in page, f"rigfem {name} {opt} is not in the CLI reference"


def test_scene_reference_has_every_key_with_a_note():
    page, missing = GEN.scene_reference()
    assert missing == [], f"scene keys without a note in docs/gen.py SCENE_NOTES: {missing}"
    from rigfem.schema import CheckTable, FourBar, SliderCrank

    for model in (CheckTable, FourBar, SliderCrank):
        for key in model.model_fields:
            assert f"| `{key}` |" in page, key
    # a note for a key the schema does not have is stale
    keys = set(re.findall(r"^\| `(\w+)` \|", page, re.M))
    stale = [k for k in GEN.SCENE_NOTES if k.rsplit(".", 1)[-1] not in keys]
    assert stale == [], f"SCENE_NOTES names keys the schema lacks: {stale}"


def test_a_key_without_a_note_is_caught():
    notes = dict(GEN.SCENE_NOTES)
    del notes["check.fidelity"]
    assert GEN.scene_reference(notes)[1] == ["check.fidelity"]


# ------------------------------------------------------------------------------------- snippets
BLOCKS = all_blocks()
PYTHON = [b for b in BLOCKS if b.lang == "python"]
TOML = [b for b in BLOCKS if b.lang == "toml"]
#: a stand-in for dask-jobqueue's SLURMCluster (no batch system here): a scheduler on loopback in the snippet's
#: process, and each "job" a `dask worker` process, as a batch job would start it (at most 2 here)
SLURM_STUB = '''import atexit, os, shutil, signal, subprocess, sys
from pathlib import Path

from distributed import LocalCluster

DASK = shutil.which("dask", path=str(Path(sys.executable).parent)) or shutil.which("dask")


class SLURMCluster(LocalCluster):
    def __init__(self, cores=1, processes=1, memory="4GiB", walltime=None):
        super().__init__(n_workers=0, processes=False, protocol="tcp://", host="127.0.0.1", dashboard_address=None)
        self.cores, self.memory, self.jobs = cores, memory, []
        atexit.register(self.end_jobs)

    def scale(self, n=None, jobs=0, **kw):  # the jobs have started: their workers are there when it returns
        k = min(jobs or n or 0, 2)
        for i in range(len(self.jobs), k):
            self.jobs.append(subprocess.Popen(
                [DASK, "worker", self.scheduler_address, "--nthreads", str(self.cores), "--memory-limit",
                 self.memory, "--host", "127.0.0.1", "--no-dashboard", "--name", f"job{i}"],
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True))
        if k:
            self.wait_for_workers(k, timeout=120)
        return k

    def end_jobs(self):
        for p in self.jobs:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
                p.wait(timeout=30)
'''
#: snippets that need more than a temporary folder: (first line that names the snippet) -> (why, files it needs,
#: heavy). A heavy snippet runs with the heavy tests (CI's second run), never skipped.
NEEDS = {"from dask_jobqueue import SLURMCluster": ("the whole four-bar sweep on a batch cluster: a local one "
                                                     "stands in for SLURM", {"dask_jobqueue.py": SLURM_STUB}, True)}


def _needs(b: Block) -> tuple[str, dict, bool]:
    return next((v for k, v in NEEDS.items() if b.text.startswith(k)), ("", {}, False))


def test_there_are_snippets():
    assert len(PYTHON) >= 4 and any(b.page == "README.md" and b.output for b in PYTHON)
    assert {k for k in NEEDS} <= {b.text.split("\n")[0] for b in PYTHON}, "a NEEDS entry matches no snippet"


def run_snippet(b: Block, tmp: pathlib.Path) -> subprocess.CompletedProcess:
    """Run a page's Python block as a reader would: in a fresh folder holding examples/ and every file
    the page names with ``title="NAME"``; a block titled ``test_*.py`` runs under pytest."""
    work = tmp / "work"
    shutil.copytree(ROOT / "examples", work / "examples")
    for other in BLOCKS:
        if other.page == b.page and other.title:
            (work / other.title).write_text(other.text)
    for name, text in _needs(b)[1].items():
        (work / name).write_text(text)
    env = sandbox_env(tmp)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(work), env.get("PYTHONPATH", "")) if p)
    if b.title and b.title.startswith("test_"):
        cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", b.title]
    else:
        (work / "snippet.py").write_text(b.text)
        cmd = [sys.executable, "snippet.py"]
    return subprocess.run(cmd, cwd=work, capture_output=True, text=True, timeout=1800, env=env)


def _check_snippet(b: Block, tmp: pathlib.Path) -> None:
    r = run_snippet(b, tmp)
    assert r.returncode == 0, f"{b.id}: the Python block exits {r.returncode}:\n{r.stdout[-1500:]}\n{r.stderr[-3000:]}"
    if b.output is not None:
        ok = doctest.OutputChecker().check_output(b.output, r.stdout, doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
        assert ok, f"{b.id} prints\n{r.stdout}\nbut the page shows\n{b.output}"


@pytest.mark.parametrize("b", [b for b in PYTHON if not _needs(b)[2]], ids=lambda b: b.id)
def test_python_snippet_runs(b, tmp_path):
    _check_snippet(b, tmp_path)


@pytest.mark.heavy
@pytest.mark.parametrize("b", [b for b in PYTHON if _needs(b)[2]], ids=lambda b: b.id)
def test_heavy_python_snippet_runs(b, tmp_path):
    _check_snippet(b, tmp_path)


def test_a_snippet_that_raises_or_prints_otherwise_fails(tmp_path):
    """The runner fails a snippet that raises, and one whose output differs from the page's."""
    raises = Block("x.md", 1, "python", None, "import rigfem.no_such_module\n")
    with pytest.raises(AssertionError, match="exits 1"):
        _check_snippet(raises, tmp_path / "a")
    differs = Block("x.md", 1, "python", None, "print('peak 157.4 MPa')\n", output="peak 157.3 MPa\n")
    with pytest.raises(AssertionError, match="but the page shows"):
        _check_snippet(differs, tmp_path / "b")


@pytest.mark.parametrize("b", TOML, ids=lambda b: b.id)
def test_toml_block_is_a_valid_scene(b):
    from rigfem.schema import validate_scene

    validate_scene(tomllib.loads(b.text), b.id)
