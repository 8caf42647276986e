"""Every command README.md and the docs show runs as written (issue 24 §7, issue 37 §7), so neither can
drift from the CLI: commands are taken from the pages' indented and fenced code blocks, from
``… && rigfem …`` lines and from every inline `rigfem …` span (tables included).

- A concrete ``rigfem`` command runs in one temporary folder (holding the pages' inputs, ``examples/``),
  in reading order (README, then the docs in the order of their nav: a later command may read what
  an earlier one wrote), with ``HOME`` and ``RIGFEM_CACHE`` in temporary folders (never the user's
  cache: ``rigfem cache --clear`` is among them), and must end with the exit code its ``# exit N``
  comment says (if none: 0 or 1, a verdict, and no error line).
- A synopsis or a mention (placeholders such as SCENE, ``[..]``, ``a|b``, ``…``, or an option
  without its value) cannot run: every option it names must exist in that command's parser.
- The commands too long for the default test run are listed in :data:`LONG` by name with the
  reason, and run with the cheap override given there; none is skipped silently.
- Every other command (``python benchmarks/…``, ``mkdocs …``, ``bash tests/run.sh``) is one the test
  suite runs elsewhere (:data:`ELSEWHERE`) or a benchmark or tool script whose options exist in it.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from docs_pages import DOCS, ROOT, pages, sandbox_env

_CHECK_FAST = ["--parts", "plate_A", "--modes", "original", "--fidelity", "draft", "--frames", "0", "--quiet"]

#: command as a page writes it -> (why it is too long for the default run, the cheap override appended)
LONG = {
    "rigfem check --force": ("a full standard check of every part, both modes (~2 min cold)", _CHECK_FAST),
    "rigfem check final-cm --force": ("a full standard check of every part, both modes (~2 min cold)", _CHECK_FAST),
    "rigfem check final-nc --allow-rule-violations --fidelity draft":
        ("every part, both modes, 12 frames (~1 min cold)", _CHECK_FAST),
    "rigfem check final-cm --force --fidelity draft": ("every part, both modes, 12 frames (~1 min cold)", _CHECK_FAST),
    "rigfem synthesize motion --points 0,0 -15.12,-9 -29.128,-4 --rig --top 3":
        ("stress verdicts of the ranked configurations (FE of every part, minutes)", ["--no-stress"]),
    "rigfem check trainer.toml": ("every part of the synthesised configuration (~1 min cold)", _CHECK_FAST),
    "rigfem synthesize function x*log(x) --x 1 3 --input 20 60 --output 80 45 --ground 2 --rig --top 3":
        ("stress verdicts of the ranked configurations (FE of every part, minutes)", ["--no-stress"]),
    "rigfem synthesize motion --points 0,0 -15.12,-9 -29.128,-4 --rig --top 3 --scene-out trainer.toml":
        ("stress verdicts of the ranked configurations (FE of every part, minutes)", ["--no-stress"]),
    "rigfem convergence final-cm --force": ("h and p refinement of six parts (hours)",
                                    ["--mode", "original", "--levels", "3", "--ratio", "2", "--extra-levels", "0",
                                     "--no-presets", "--max-gib", "1"]),
    "rigfem verify --against calculix final-cm --fidelity draft --threads 1":
        ("CalculiX on 12 part cases (~80 s)", None),
    "rigfem sweep --four-bar": ("51 156 configurations, 3 306 with FE (~3 min, ~5 GB)", None),
}
#: mentions that name a file the reader makes (no command of the pages writes it)
READER_FILES = {"rigfem check best.toml": "best.toml is the reader's own --scene-out file"}
_PLACEHOLDER = re.compile(r"\[|\\\||…|\.\.|\b(SCENE|PART|FILE|DIR|HOST|PORT|N|P|MM|G|R|DEG|EXPR|NAME)\b|\|")

#: commands other than ``rigfem …`` that the pages show, and the test that runs each
ELSEWHERE = {
    r"pip install -e \. && rigfem check --force": "the rigfem part runs here; the install: tests/test_install.py "
                                                  "(a regular install), tests/run.sh --editable",
    r"bash tests/run\.sh": ".ci/run runs it (tests/test_ci.py::test_ci_runs_the_readme_test_command_then_the_heavy_tests)",
    r"bash tests/run\.sh -m heavy": ".ci/run runs it (tests/test_ci.py)",
    r'pip install -e "\.\[docs\]"': "pyproject.toml's docs extra (test_the_docs_extra_builds_the_site)",
    r"mkdocs build --strict --site-dir \S+": "tests/test_docs.py::test_site_builds_strict",
    r"dask (scheduler|worker) --scheduler-file \S+( --nthreads 1)?": "tests/test_sweep_distributed.py (heavy) "
                                                                      "starts Dask's own programs",
    r"python benchmarks/publish\.py( --check)?": "tests/test_figures.py::test_readme_and_tables_agree_with_the_records",
}


def page_order() -> list[str]:
    """README, then the docs' pages in the order of mkdocs.yml's nav, then the rest (generated pages)."""
    nav = re.findall(r":\s*(\S+\.md)\s*$", (ROOT / "mkdocs.yml").read_text(), re.M)
    known = pages()
    order = ["README.md"] + [f"docs/{p}" for p in nav if f"docs/{p}" in known]
    return order + sorted(set(known) - set(order))


def _block_lines(text: str):
    """(line number, line) of the pages' code: indented blocks (4 spaces, not a list's continuation) and
    fenced shell blocks, continuations joined."""
    lines = text.splitlines()
    fenced, i = None, 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("```"):
            fenced = None if fenced is not None else line[3:].split(" ")[0]
            i += 1
            continue
        code = (fenced in ("bash", "console", "sh", "shell") or
                fenced is None and line.startswith("    ") and not line.strip().startswith(("#", "-", "|", "*")))
        if code and line.strip():
            text_ = line.strip().removeprefix("$ ")
            start = i
            while text_.endswith("\\") and i + 1 < len(lines):
                i += 1
                text_ = text_[:-1].rstrip() + " " + lines[i].strip()
            yield start, text_
        i += 1


def _commands(text: str) -> list[str]:
    """A page's rigfem commands, in order, as single lines (continuations joined, comments kept)."""
    found: list[tuple[int, str]] = []
    for i, line in _block_lines(text):
        if "rigfem " in line:
            cmd = line[line.index("rigfem "):]
            if line.startswith("rigfem ") or "&& rigfem" in line:
                found.append((i, cmd))
    spans = [(text[: m.start()].count("\n"), m.group(1)) for m in re.finditer(r"`(rigfem [^`]*)`", text)]
    return [c for _, c in sorted(found + spans)]


def _others(text: str) -> list[str]:
    """A page's other commands: code lines of other programs, and inline `python benchmarks/…` spans."""
    progs = ("python ", "pip ", "bash ", "mkdocs ", "dask ", "pytest ")
    out = [line.split("  #")[0].strip() for _, line in _block_lines(text) if line.startswith(progs)]
    return out + re.findall(r"`(python (?:benchmarks|examples|tools)/[^`]*)`", text)


def _split(cmd: str) -> tuple[list[str], set[int]]:
    """(argv after ``rigfem``, the exit codes allowed: the one its ``# exit N`` comment names, else
    0 or 1, a verdict either way)."""
    code = re.search(r"#\s*exit (\d)", cmd)
    argv = shlex.split(cmd.split("#")[0].strip())
    return argv[1:], {int(code.group(1))} if code else {0, 1}


def _runnable(cmd: str) -> bool:
    if cmd in READER_FILES:
        return False
    argv, _ = _split(cmd)
    if _PLACEHOLDER.search(cmd.split("#")[0]):
        return False
    from rigfem.cli import build_parser

    try:
        with open(os.devnull, "w") as null:
            old, sys.stderr, sys.stdout = (sys.stderr, sys.stdout), null, null
            try:
                build_parser(argv).parse_args(argv)
            finally:
                sys.stderr, sys.stdout = old
    except SystemExit as exc:
        return exc.code == 0   # --version, --help run; else a mention (an option without its value)
    return True


PAGES = pages()
ORDER = page_order()
#: (page, command) in reading order
COMMANDS = [(p, c) for p in ORDER for c in _commands(PAGES[p])]
OTHERS = sorted({(p, c) for p in ORDER for c in _others(PAGES[p])})
#: run in the default test run: the long commands without a cheap override run in the heavy test below
RUN = [(p, c) for p, c in COMMANDS
       if _runnable(c) and LONG.get(" ".join(["rigfem", *_split(c)[0]]), (0, 0))[1] is not None]
#: page commands that take over 10 s even in their cheap form: run by the heavy stage (``-m heavy``,
#: in reading order among themselves: the synthesis writes trainer.toml, the check after it reads it)
SLOW = ("rigfem convergence final-cm --force", "rigfem kinematics --samples 1000000 --json",
        "rigfem synthesize ", "rigfem check trainer.toml",
        "rigfem kinematics mech2-fourbar-coupler-point --plot")
SYNOPSES = [(p, c) for p, c in COMMANDS if (p, c) not in RUN]
_id = lambda pc: f"{pc[0]}: {pc[1]}"  # noqa: E731


def test_pages_have_commands_and_every_long_one_is_on_a_page():
    assert len(RUN) >= 15 and len(SYNOPSES) >= 10
    assert {p for p, _ in RUN} >= {"README.md", "docs/guide/check.md", "docs/guide/cache.md"}
    norm = {" ".join(["rigfem", *_split(c)[0]]) for _, c in COMMANDS}
    assert set(LONG) <= norm, set(LONG) - norm


def test_the_docs_pages_are_read():
    """The commands come from every written page, and a command on a docs page is found."""
    assert len([p for p in PAGES if p.startswith("docs/") and "(generated)" not in p]) >= 15
    assert ("docs/guide/cache.md", "rigfem cache --clear") in COMMANDS
    assert _commands("    rigfem parts\n\n```bash\nrigfem cache  # exit 0\n```\n") == ["rigfem parts",
                                                                                       "rigfem cache  # exit 0"]


@pytest.mark.parametrize("pc", SYNOPSES, ids=_id)
def test_every_option_a_page_names_exists(pc):
    from rigfem.cli import build_parser

    page, cmd = pc
    text = cmd.split("#")[0]
    words = [w for w in re.split(r"[\s\[\]|\\]+", text) if w]
    sub = next((w for w in words[1:] if not w.startswith("-")), None)
    parser = build_parser([sub] if sub else [])
    known = set(parser._option_string_actions)
    for action in parser._actions:
        for choice in (getattr(action, "choices", None) or {}).values() if isinstance(
                getattr(action, "choices", None), dict) else []:
            known |= set(choice._option_string_actions)
            for a2 in choice._actions:
                if isinstance(getattr(a2, "choices", None), dict):
                    for c2 in a2.choices.values():
                        known |= set(c2._option_string_actions)
    for w in words:
        opt = w.split("=")[0]
        if opt.startswith("--"):
            assert opt in known, f"{page} names {opt} in `{cmd}`, which rigfem {sub or ''} does not have"


@pytest.fixture(scope="module")
def sandbox(tmp_path_factory):
    """One temporary folder for the pages' commands, in reading order, with their input files; HOME and
    RIGFEM_CACHE in temporary folders beside it."""
    base = tmp_path_factory.mktemp("pages")
    work = base / "work"
    shutil.copytree(ROOT / "examples", work / "examples")
    return work, sandbox_env(base)


def test_the_commands_run_in_a_sandbox(sandbox):
    """No command of the pages sees the user's cache or home: `rigfem cache --clear` clears the sandbox's."""
    work, env = sandbox
    assert env["RIGFEM_CACHE"] != os.environ.get("RIGFEM_CACHE") and env["HOME"] != os.environ.get("HOME")
    assert Path(env["RIGFEM_CACHE"]).parent == work.parent == Path(env["HOME"]).parent
    r = subprocess.run([sys.executable, "-m", "rigfem", "cache"], cwd=work, capture_output=True, text=True, env=env)
    assert r.returncode == 0 and env["RIGFEM_CACHE"] in r.stdout


@pytest.mark.parametrize("pc", [pytest.param(pc, marks=pytest.mark.heavy) if pc[1].startswith(SLOW) else pc
                                for pc in RUN], ids=_id)
def test_page_command_runs_as_written(sandbox, pc):
    page, cmd = pc
    work, env = sandbox
    argv, code = _split(cmd)
    key = " ".join(["rigfem", *argv])
    if key in LONG:
        argv = argv + LONG[key][1]
    r = subprocess.run([sys.executable, "-m", "rigfem", *argv], cwd=work, capture_output=True, text=True,
                       timeout=900, env=env)
    assert r.returncode in code, f"{page}: `{cmd}` -> exit {r.returncode}: {r.stderr[-600:]}"
    assert "Traceback" not in r.stderr and "internal error" not in r.stderr
    assert 2 in code or "rigfem: error" not in r.stderr


@pytest.mark.heavy
@pytest.mark.parametrize("cmd", [c for c in LONG if LONG[c][1] is None])
def test_long_page_command_runs_as_written(tmp_path, cmd):
    argv, code = _split(cmd)
    r = subprocess.run([sys.executable, "-m", "rigfem", *argv], cwd=tmp_path,
                       capture_output=True, text=True, timeout=7200, env=sandbox_env(tmp_path / "sandbox"))
    assert r.returncode in code, r.stderr[-600:]


@pytest.mark.parametrize("pc", OTHERS, ids=_id)
def test_every_other_command_is_run_elsewhere(pc):
    """A command of another program is one the suite runs elsewhere, an example (tests/test_examples.py) or a
    benchmark script whose every option exists."""
    page, cmd = pc
    if any(re.fullmatch(rx, cmd) for rx in ELSEWHERE):
        return
    m = re.fullmatch(r"python (benchmarks|examples|tools)/(\w+)\.py(.*)", cmd)
    assert m, f"{page} shows `{cmd}`: no test runs it (add it to ELSEWHERE with the test that does)"
    script = ROOT / m[1] / f"{m[2]}.py"
    assert script.is_file(), f"{page}: `{cmd}` names {script.relative_to(ROOT)}, which does not exist"
    src = script.read_text()
    for opt in re.findall(r"(?<!\S)(--[\w-]+)", m[3]):
        assert f'"{opt}"' in src, f"{page}: `{cmd}`: {script.name} has no option {opt}"


def test_the_docs_extra_builds_the_site():
    import tomllib

    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    names = {re.match(r"[\w-]+", d).group() for d in extras["docs"]}
    assert {"mkdocs", "mkdocs-material"} <= names
    assert names <= {re.match(r"[\w-]+", d).group() for d in extras["test"]}, "tests/run.sh installs the test extra"
    assert DOCS.is_dir()
