"""Every ``rigfem`` command README.md shows runs as written (issue 24 §7), so README cannot drift
from the CLI: commands are taken from README's indented blocks, from ``… && rigfem …`` lines and
from every inline `rigfem …` span (tables included).

- A concrete command runs in a temporary folder (holding README's inputs, ``examples/``), in
  README order (a later command may read what an earlier one wrote), and must end with the exit
  code its ``# exit N`` comment says (if none: 0 or 1, a verdict, and no error line).
- A synopsis or a mention (placeholders such as SCENE, ``[..]``, ``a|b``, ``…``, or an option
  without its value) cannot run: every option it names must exist in that command's parser.
- The commands too long for the default test run are listed in :data:`LONG` by name with the
  reason, and run with the cheap override given there; none is skipped silently.
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

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
_CHECK_FAST = ["--parts", "plate_A", "--modes", "original", "--fidelity", "draft", "--frames", "0", "--quiet"]

#: command as README writes it -> (why it is too long for the default run, the cheap override appended)
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
#: mentions that name a file the reader makes (no README command writes it)
READER_FILES = {"rigfem check best.toml": "best.toml is the reader's own --scene-out file"}
_PLACEHOLDER = re.compile(r"\[|\\\||…|\.\.|\b(SCENE|PART|FILE|DIR|HOST|PORT|N|P|MM|G|R|DEG|EXPR)\b|\|")


def _commands() -> list[str]:
    """README's rigfem commands, in order, as single lines (continuations joined, comments cut)."""
    found: list[tuple[int, str]] = []
    lines = README.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("    ") and "rigfem " in line and not line.strip().startswith(("#", "-", "|")):
            text = line.strip()
            while text.endswith("\\") and i + 1 < len(lines):
                i += 1
                text = text[:-1].rstrip() + " " + lines[i].strip()
            cmd = text[text.index("rigfem "):]
            if cmd.startswith("rigfem ") and (text.startswith("rigfem ") or "&& rigfem" in text):
                found.append((i, cmd))
        i += 1
    spans = [(README[: m.start()].count("\n"), m.group(1)) for m in re.finditer(r"`(rigfem [^`]*)`", README)]
    return [c for _, c in sorted(found + spans)]


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


COMMANDS = _commands()
#: run in the default test run: the long commands without a cheap override run in the heavy test below
RUN = [c for c in COMMANDS if _runnable(c) and LONG.get(" ".join(["rigfem", *_split(c)[0]]), (0, 0))[1] is not None]
SYNOPSES = [c for c in COMMANDS if c not in RUN]


def test_readme_has_commands_and_every_long_one_is_in_readme():
    assert len(RUN) >= 15 and len(SYNOPSES) >= 10
    norm = {" ".join(["rigfem", *_split(c)[0]]) for c in COMMANDS}
    assert set(LONG) <= norm, set(LONG) - norm


@pytest.mark.parametrize("cmd", SYNOPSES)
def test_every_option_readme_names_exists(cmd):
    from rigfem.cli import build_parser

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
            assert opt in known, f"README names {opt} in `{cmd}`, which rigfem {sub or ''} does not have"


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """One temporary folder for README's commands, in order, with README's input files."""
    d = tmp_path_factory.mktemp("readme")
    shutil.copytree(ROOT / "examples", d / "examples")
    return d


@pytest.mark.parametrize("cmd", RUN)
def test_readme_command_runs_as_written(folder, cmd):
    argv, code = _split(cmd)
    key = " ".join(["rigfem", *argv])
    if key in LONG:
        argv = argv + LONG[key][1]
    env = {**os.environ, "BROWSER": "/bin/false", "DISPLAY": ""}
    r = subprocess.run([sys.executable, "-m", "rigfem", *argv], cwd=folder, capture_output=True, text=True,
                       timeout=900, env=env)
    assert r.returncode in code, f"`{cmd}` -> exit {r.returncode}: {r.stderr[-600:]}"
    assert "Traceback" not in r.stderr and "internal error" not in r.stderr
    assert 2 in code or "rigfem: error" not in r.stderr


@pytest.mark.heavy
@pytest.mark.parametrize("cmd", [c for c in LONG if LONG[c][1] is None])
def test_long_readme_command_runs_as_written(tmp_path, cmd):
    argv, code = _split(cmd)
    r = subprocess.run([sys.executable, "-m", "rigfem", *argv], cwd=tmp_path, capture_output=True, text=True,
                       timeout=7200)
    assert r.returncode in code, r.stderr[-600:]
