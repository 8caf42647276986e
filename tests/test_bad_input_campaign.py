"""Issue 24 "done when": another round of bad input over every command — each refused with exit 2
and one line naming the field (no traceback, nothing written), and hypothesis over the numbers
of synthesize function and kinematics: never an internal error, never exit 3 on valid input."""

from __future__ import annotations

import os

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rigfem.cli import main
from said import one_line, said

SYN = ["synthesize", "function"]
F = ["--input", "20", "90", "--output", "80", "90", "--ground", "2"]

CASES = [
    (["sweep", "--samples", "-5", "--out", "o"], "samples = -5"),
    (["sweep", "--speed-hz", "inf", "--out", "o"], "speed_hz = inf"),
    (["sweep", "--chunk-size", "0", "--out", "o"], "--chunk-size = 0"),
    (["sweep", "--workers", "0", "--out", "o"], "--workers = 0"),
    (["sweep", "--samples", "100000", "--out", "o"], "more than the limit of 24 h"),
    (["sweep", "--scheduler", "tcp://localhost:99999", "--out", "o"], "--scheduler port = 99999"),
    (["sweep", "--scheduler", "http://x", "--out", "o"], "must be tcp://HOST:PORT"),
    (["sweep", "--slider-crank", "--model", "original", "--out", "o"], "model = 'original'"),
    ([*SYN, "x", "--x", "nan", "2", *F], "--x X0 = 'nan'"),
    ([*SYN, "x", "--x", "1", "inf", *F], "--x X1 = 'inf'"),
    ([*SYN, "x**2", "--x", "1", "2", "--input", "20", "0", "--output", "80", "90", "--ground", "2"],
     "--input RANGE = 0"),
    ([*SYN, "x**2", "--x", "1", "2", "--input", "20", "360", "--output", "80", "90", "--ground", "2"],
     "--input RANGE = 360"),
    ([*SYN, "x**2", "--x", "1", "2", "--input", "20", "90", "--output", "80", "90", "--ground", "0"], "--ground = '0'"),
    ([*SYN, "x**2", "--x", "1", "2", *F, "--rig", "--top", "0"], "--top = '0'"),
    ([*SYN, "x**2", "--x", "1", "2", *F, "--top", "3"], "--top needs --rig"),
    ([*SYN, "x**2", "--x", "1", "2", *F, "--rig", "--fidelity", "ultra"], "--fidelity = 'ultra'"),
    ([*SYN, "1/(x-1.5)", "--x", "1", "2", *F], "not finite at x = 1.5"),
    ([*SYN, "exp(x)", "--x", "0", "1000", *F], "not finite at x = 710"),
    ([*SYN, "sqrt(x)", "--x", "-1", "1", *F], "not finite at x = -1"),
    ([*SYN, "(" * 500 + "x" + ")" * 500, "--x", "0", "1", *F], "nests parentheses 500 deep"),
    ([*SYN, "x**2", "--x", "1e300", "1.0000001e300", *F], "--x X0 = '1e300'"),
    ([*SYN, "x**3", "--x", "2", "2.0000001", *F], "--x X0 X1 = 2 2.0000001"),
    ([*SYN, "x**2", "--x", "-1e16", "1", *F], "--x X0 = '-1e16'"),      # a negative number, not an option
    (["kinematics", "--slider-crank", "300", "200", "--at", "-inf"], "--at = '-inf'"),
    (["synthesize", "motion", "--points", "0,0", "0,0", "1,1"], "coincide"),
    (["synthesize", "motion", "--points", "0,0", "1,nan", "2,2"], "--points Y = 'nan'"),
    (["kinematics", "--four-bar", "0", "1", "1", "1"], "B2 = '0'"),
    (["kinematics", "--slider-crank", "100", "50", "--offset", "1e9"], "--offset = '1e9'"),
    (["kinematics", "--slider-crank", "100", "300", "--at", "nan"], "--at = 'nan'"),
    (["kinematics", "--four-bar", "100", "300", "300", "300", "--samples", "1e9"], "--samples = '1e9'"),
    (["kinematics", "--four-bar", "100", "300", "300", "300", "--omega", "0"], "--omega must be non-zero"),
    (["kinematics", "--slider-crank", "300", "200", "--at", "90"], "--at = 90 deg"),
    (["reactions", "--samples", "7"], "--samples = '7'"),
    (["check", "--size", "nan", "--out", "o"], "[check].size_mm = nan"),
    (["check", "--parts", "nope", "--out", "o"], "'nope' is not a part"),
    (["verify", "--peak-tol", "-1"], "--peak-tol = '-1'"),
    (["verify", "final-nc"], "--allow-rule-violations"),
    (["convergence", "--ratio", "5", "--out", "o"], "--ratio = '5'"),
    (["convergence", "final-nc", "--out", "o"], "--allow-rule-violations"),
]


@pytest.mark.parametrize("argv,needle", CASES, ids=[" ".join(a)[:60] for a, _ in CASES])
def test_bad_input_is_one_line_naming_the_field(argv, needle, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert one_line(err).startswith("rigfem: error: ") and needle in err, err
    assert os.listdir(tmp_path) == []   # nothing written


FAST = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


@FAST
@given(x0=st.floats(-1e6, 1e6), width=st.floats(1e-12, 10.0),
       expr=st.sampled_from(["x**2", "x**3 + 1", "exp(x/1e6)", "x", "sin(x) + 2"]))
def test_synthesize_function_never_fails_to_compute(capsys, x0, width, expr):
    x1 = x0 + width
    if not x1 > x0:
        return
    rc = main([*SYN, expr, "--x", repr(x0), repr(x1), *F])
    err = capsys.readouterr().err
    assert rc in (0, 1, 2) and "internal error" not in err and "could not compute" not in err, err


@FAST
@given(b2=st.floats(10, 1000), b3=st.floats(10, 1000), off=st.floats(-500, 500), at=st.floats(-720, 720))
def test_slider_crank_at_any_angle_computes_or_names_its_range(capsys, b2, b3, off, at):
    rc = main(["kinematics", "--slider-crank", repr(b2), repr(b3), "--offset", repr(off), "--at", repr(at)])
    err = capsys.readouterr().err
    assert rc in (0, 2) and "internal error" not in err, err
    assert rc == 0 or len(said(err)) == 1


def test_sweep_scheduler_address_that_answers_but_is_not_dask(tmp_path, monkeypatch, capsys):
    """A port that accepts TCP and answers garbage (a proxy, a web server) is not a scheduler:
    exit 3 in seconds, before any work and before the output folder is made."""
    import socket
    import threading
    import time

    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]

    def answer() -> None:
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            conn.sendall(b"HTTP/1.1 400 Bad Request\r\n\r\n" * 4)
            conn.close()

    threading.Thread(target=answer, daemon=True).start()
    monkeypatch.chdir(tmp_path)
    t0 = time.monotonic()
    try:
        assert main(["sweep", "--scheduler", f"tcp://127.0.0.1:{port}", "--quiet", "--out", "sw"]) == 3
    finally:
        server.close()
    err = capsys.readouterr().err
    assert "answers, but not as a Dask scheduler" in err and time.monotonic() - t0 < 30
    assert os.listdir(tmp_path) == []
