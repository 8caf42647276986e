"""Issue 38, names and sizes: every numeric option of every command has its range checked where
it is read (exit 2, one line naming it: the option, or the field it sets), before anything is computed: ``rigfem mesh PART --size
1e-300`` divided by zero and ``--size 1e300`` overflowed (exit 3) before.  A value inside the
range is computed or refused as bad input, never an internal error (the linkages, whose every
length is cheap to try, are searched by hypothesis)."""

from __future__ import annotations

import argparse
import math

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from rigfem.cli import COMMANDS, build_parser, main
from said import one_line

FAST = ["--parts", "plate_A", "--modes", "original", "--fidelity", "draft", "--frames", "0", "--quiet"]
FUNC = ["synthesize", "function", "x*log(x)", "--x", "1", "3", "--input", "20", "90", "--output", "80", "90",
        "--ground", "2"]
MOTION = ["synthesize", "motion", "--points", "0,0", "-15.12,-9", "-29.128,-4"]
FOUR = ["--four-bar", "480", "840", "780", "1020"]

#: (command argv with {} where the value goes, the name its error gives, lowest, highest, whole number)
RANGES = [
    (["check", "final-cm", *FAST, "--order", "{}"], "[check].order", 1, 2, True),
    (["check", "final-cm", *FAST, "--size", "{}"], "[check].size_mm", 0.1, 100, False),
    (["check", "final-cm", *FAST, "--local-size", "{}"], "[check].local_size_mm", 0.05, 100, False),
    (["check", "final-cm", *FAST, "--samples", "{}"], "[check].samples", 36, 100_000, True),
    (["check", "final-cm", *FAST, "--frames", "{}"], "[check].frames", 0, 360, True),
    (["kinematics", "--four-bar", "{}", "840", "780", "1020"], "B2", 10, 10_000, False),
    (["kinematics", "--four-bar", "480", "840", "780", "{}"], "D", 10, 10_000, False),
    (["kinematics", "--slider-crank", "300", "{}"], "B3", 10, 10_000, False),
    (["kinematics", "--slider-crank", "300", "900", "--offset", "{}"], "--offset", -10_000, 10_000, False),
    (["kinematics", *FOUR, "--coupler-point", "{}", "30"], "--coupler-point DIST", 0, 1e5, False),
    (["kinematics", *FOUR, "--coupler-point", "100", "{}"], "--coupler-point ANGLE", -360, 360, False),
    (["kinematics", "--omega", "{}"], "--omega", -1e4, 1e4, False),
    (["kinematics", "--alpha", "{}"], "--alpha", -1e7, 1e7, False),
    (["kinematics", "--at", "{}"], "--at", -3600, 3600, False),
    (["kinematics", "--samples", "{}"], "--samples", 8, 1_000_000, True),
    (["reactions", "--four-bar", "480", "{}", "780", "1020"], "B3", 10, 10_000, False),
    (["reactions", "--slider-crank", "{}", "900"], "B2", 10, 10_000, False),
    (["reactions", "--slider-crank", "300", "900", "--offset", "{}"], "--offset", -10_000, 10_000, False),
    (["reactions", "--speed-hz", "{}"], "--speed-hz", 0, 100, False),
    (["reactions", "--samples", "{}"], "--samples", 8, 1_000_000, True),
    (["mesh", "PF_4b_006", "--out", "p.vtu", "--size", "{}"], "--size", 0.01, 10_000, False),
    (["mesh", "PF_4b_006", "--out", "p.vtu", "--local-size", "{}"], "--local-size", 0.001, 10_000, False),
    (["mesh", "rail_size25", "--out", "p.vtu", "--length", "{}"], "--length", 0, 1e6, False),
    (["mesh", "rail_size25", "--out", "p.vtu", "--set", "width={}"], "--set width", -1e6, 1e6, False),
    (["mesh", "PF_4b_006", "--out", "p.vtu", "--min-quality", "{}"], "--min-quality", 0, 1, False),
    (["mesh", "PF_4b_006", "--out", "p.vtu", "--order", "{}"], "--order", 1, 2, True),
    (["convergence", "plate_A", "--levels", "{}"], "--levels", 3, 8, True),
    (["convergence", "plate_A", "--ratio", "{}"], "--ratio", 1.1, 2, False),
    (["convergence", "plate_A", "--max-gib", "{}"], "--max-gib", 0.5, 1024, False),
    (["convergence", "plate_A", "--extra-levels", "{}"], "--extra-levels", 0, 3, True),
    (["verify", "--threads", "{}"], "--threads", 1, 64, True),
    (["verify", "--peak-tol", "{}"], "--peak-tol", 0, 100, False),
    (["verify", "--disp-tol", "{}"], "--disp-tol", 0, 100, False),
    (["sweep", "--quiet", "--speed-hz", "{}"], "speed_hz", 0, 100, False),
    (["sweep", "--quiet", "--samples", "{}"], "samples", 36, 100_000, True),
    (["sweep", "--quiet", "--workers", "{}"], "--workers", 1, 256, True),
    (["sweep", "--quiet", "--chunk-size", "{}"], "--chunk-size", 1, 100_000, True),
    (["synthesize", "function", "x*log(x)", "--x", "{}", "3", "--input", "20", "90", "--output", "80", "90",
      "--ground", "2"], "--x X0", -1e15, 1e15, False),
    ([*FUNC[:6], "--input", "20", "{}", "--output", "80", "90", "--ground", "2"], "--input RANGE", -360, 360, False),
    ([*FUNC[:6], "--input", "20", "90", "--output", "{}", "90", "--ground", "2"], "--output START", -360, 360, False),
    ([*FUNC[:12], "--ground", "{}"], "--ground", 0, 1e9, False),
    ([*FUNC, "--points", "{}"], "--points", 3, 3, True),
    ([*FUNC, "--rig", "--no-stress", "--top", "{}"], "--top", 1, 50, True),
    (["synthesize", "motion", "--points", "{},0", "-15.12,-9", "-29.128,-4"], "--points X", -1e9, 1e9, False),
    ([*MOTION, "--coupler-rotations", "{}", "7.8", "--crank-rotations", "218", "-227", "--rocker-rotations", "7",
      "2"], "--coupler-rotations", -360, 360, False),
    ([*MOTION, "--coupler-rotations", "4.9", "7.8", "--crank-rotations", "{}", "-227", "--rocker-rotations", "7",
      "2"], "--crank-rotations", -360, 360, False),
    ([*MOTION, "--coupler-rotations", "4.9", "7.8", "--crank-rotations", "218", "-227", "--rocker-rotations", "7",
      "{}"], "--rocker-rotations", -360, 360, False),
    ([*MOTION, "--rig", "--no-stress", "--scale", "{}"], "--scale", 0, 1e4, False),
]
#: options that take a value that is not a number (or a list of numbers checked above)
NOT_NUMBERS = {"--out", "--fidelity", "--modes", "--parts", "--model", "--reactions-csv", "--solver", "--csv",
               "--plot", "--animate", "--branch", "--refine", "--mode", "--against", "--scheduler", "--scene-out",
               "--author", "--pdf"}
NUMBERS = {"--order", "--size", "--local-size", "--samples", "--frames", "--four-bar", "--slider-crank", "--offset",
           "--coupler-point", "--omega", "--alpha", "--at", "--speed-hz", "--length", "--set", "--min-quality",
           "--levels", "--ratio", "--max-gib", "--extra-levels", "--threads", "--peak-tol", "--disp-tol", "--workers",
           "--chunk-size", "--x", "--input", "--output", "--ground", "--points", "--top", "--coupler-rotations",
           "--crank-rotations", "--rocker-rotations", "--scale"}


def _options(parser: argparse.ArgumentParser) -> set[str]:
    out = set()
    for a in parser._actions:
        if isinstance(a, argparse._SubParsersAction):
            for sub in a.choices.values():
                out |= _options(sub)
        elif a.option_strings and a.nargs != 0 and not isinstance(a, argparse._HelpAction):
            out.add(a.option_strings[0])
    return out


def _option(argv: list[str]) -> str:
    """The option whose value holds the ``{}``."""
    i = next(k for k, a in enumerate(argv) if "{}" in a)
    return next(a for a in reversed(argv[:i]) if a.startswith("--"))


def test_every_option_with_a_value_is_a_number_ranged_here_or_not_a_number():
    seen = set().union(*(_options(build_parser([c])) for c in COMMANDS))
    assert seen == NUMBERS | NOT_NUMBERS, (seen - NUMBERS - NOT_NUMBERS, (NUMBERS | NOT_NUMBERS) - seen)
    assert {_option(argv) for argv, *_ in RANGES} == NUMBERS


def _outside(lo: float, hi: float, whole: bool):
    """Values a user could type that lie outside [lo, hi] (or are not whole)."""
    values = st.one_of(st.floats(max_value=lo, exclude_max=True, allow_nan=False),
                       st.floats(min_value=hi, exclude_min=True, allow_nan=False),
                       st.sampled_from([math.nan, math.inf, -math.inf, 1e-300 if lo > 0 else -1e300, 1e300]))
    if whole:
        values = st.one_of(values, st.floats(min_value=lo, max_value=hi).filter(lambda v: v != int(v)))
    return values.map(lambda v: str(int(v)) if whole and math.isfinite(v) and v == int(v) and abs(v) < 1e18 else repr(v))


@pytest.mark.parametrize("argv, name, lo, hi, whole", RANGES, ids=[f"{a[0]} {n}" for a, n, *_ in RANGES])
def test_a_number_outside_its_range_is_exit_2_naming_the_option(tmp_path, capsys, monkeypatch, argv, name, lo, hi,
                                                                 whole):
    monkeypatch.chdir(tmp_path)

    @settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(value=_outside(lo, hi, whole))
    @example(value="1e-300" if lo > 0 else "-1e300")
    @example(value="1e300")
    def check(value):
        try:
            code = main([a.replace("{}", value) for a in argv])
        except SystemExit as exc:  # argparse's own refusal of a value its type cannot read (exit 2)
            code = exc.code
        err = capsys.readouterr().err
        assert code == 2, err
        line = one_line(err)
        flag = name.replace("[check].", "--").split()[0].lower()  # argparse's own refusal names the flag
        assert line.startswith("rigfem: error: ") and (name.lower() in line.lower() or flag in line.lower()), line

    check()


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(lengths=st.lists(st.sampled_from([10.0, 60.0, 300.0, 500.0, 700.0, 1020.0, 10000.0])
                        | st.floats(min_value=10.0, max_value=10000.0), min_size=4, max_size=4),
       command=st.sampled_from(["kinematics", "reactions"]))
@example(lengths=[500.0, 500.0, 500.0, 500.0], command="kinematics")   # a rhombus: change points at 0 and 180
@example(lengths=[300.0, 700.0, 700.0, 300.0], command="kinematics")   # a kite: A passes over O4
@example(lengths=[300.0, 700.0, 700.0, 300.0], command="reactions")
@example(lengths=[500.0, 500.0, 500.0, 500.0], command="reactions")
def test_any_four_bar_in_range_is_computed_or_bad_input(capsys, lengths, command):
    code = main([command, "--four-bar", *map(repr, lengths), "--samples", "36"])
    err = capsys.readouterr().err
    assert code in (0, 2) and "internal error" not in err and "could not compute" not in err, err
    if code == 2:
        assert one_line(err).startswith("rigfem: error: ")
