"""Issue 38, sizes: a file too big for what it is is refused from its size, before it is read
(a 4 GB scene file was read whole first: MemoryError under an address limit), and the largest
valid output, ``rigfem kinematics --samples 1000000 --json``, streams: it took 3.6 min and
14.8 GB for its 1.46 GB of JSON, now seconds and the memory of one chunk of angles."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time
import tracemalloc

import pytest

from rigfem.cli import main
from rigfem.errors import InputError
from said import one_line


@pytest.mark.parametrize("size", [1_000_001, 64 * 2**20, 4 * 2**30])
def test_a_scene_file_too_big_is_refused_before_it_is_read(tmp_path, size):
    from rigfem.scene import MAX_BYTES, read_toml

    big = tmp_path / "big.toml"
    with open(big, "wb") as fh:
        fh.truncate(size)   # sparse: no disk used
    tracemalloc.start()
    try:
        with pytest.raises(InputError, match=f"is {size} bytes; a scene file is at most {MAX_BYTES} bytes"):
            read_toml(big)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 2**20   # not read: the refusal allocated less than 1 MiB


def test_a_reaction_csv_too_big_is_refused_before_it_is_read(tmp_path):
    from rigfem.io.reactions_csv import MAX_BYTES, read_csv

    big = tmp_path / "big.csv"
    with open(big, "wb") as fh:
        fh.truncate(4 * 2**30)
    tracemalloc.start()
    try:
        with pytest.raises(InputError, match=f"a reaction CSV is at most {MAX_BYTES} bytes"):
            read_csv(big)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 2**20


def test_a_big_scene_on_the_command_line_is_exit_2(tmp_path, capsys):
    big = tmp_path / "big.toml"
    with open(big, "wb") as fh:
        fh.truncate(4 * 2**30)
    assert main(["kinematics", str(big)]) == 2
    assert "4294967296 bytes" in one_line(capsys.readouterr().err)


def _record(m, i: int) -> dict:
    """Angle ``i`` of the motion ``m`` as the JSON record the command printed before it streamed."""
    def num(x):
        return float(x) if math.isfinite(x) else None

    r = {"crank_deg": float(m.crank_deg[i]),
         "links": {n: {k: num(v[k][i]) for k in v} for n, v in m.links.items()},
         "points": {n: {k: [num(c) for c in v[k][i]] for k in v} for n, v in m.points.items()}}
    if m.slider is not None:
        r["slider"] = {k: num(v[i]) for k, v in m.slider.items()}
    if m.transmission_deg is not None:
        r["transmission_angle_deg"] = num(m.transmission_deg[i])
        r["mechanical_advantage"] = num(m.mechanical_advantage[i])
    return r


@pytest.mark.parametrize("argv", [["kinematics", "--samples", "1000", "--json"],
                                  ["kinematics", "mech3-inverted-slider-crank", "--json"],
                                  ["kinematics", "--slider-crank", "200", "600", "--samples", "40", "--json"]])
def test_the_json_stream_holds_every_angles_record(capsys, argv):
    """The streamed --json holds the record of every angle, as the whole result did (a general-
    solver linkage; a slider-crank whose dead centre's mechanical advantage is unbounded: null)."""
    from rigfem import linkage
    from rigfem.cli import build_parser
    from rigfem.cli.kinematics import _build

    assert main(argv) == 0
    r = json.loads(capsys.readouterr().out)
    lk, _, omega, alpha, _, _ = _build(build_parser(argv).parse_args(argv))
    m = linkage.linkage_motion(lk, [a["crank_deg"] for a in r["angles"]], omega, alpha)
    assert len(r["angles"]) == (int(argv[argv.index("--samples") + 1]) if "--samples" in argv else 360)
    assert r["angles"] == [_record(m, i) for i in range(m.crank_deg.size)]


@pytest.mark.heavy  # over 10 s: the default run stays under 10 minutes
def test_a_million_angles_stream_in_bounded_memory(tmp_path):
    """The allowed maximum: a full JSON of a million angles, read as it comes; the process's peak
    memory stays that of a chunk (it was 14.8 GB)."""
    # VmHWM: this process image's peak (ru_maxrss would carry the parent's over exec)
    code = ("import sys; from rigfem.cli import main; c = main(sys.argv[1:]); "
            "hwm = next(l.split()[1] for l in open('/proc/self/status') if l.startswith('VmHWM')); "
            "sys.stderr.write(f'peak {hwm}\\n'); sys.exit(c)")
    t0 = time.perf_counter()
    p = subprocess.Popen([sys.executable, "-c", code, "kinematics", "--samples", "1000000", "--json"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path)
    key = b'{"crank_deg"'  # a record's start (a toggle of the turn has a crank_deg too)
    rows, size, tail = 0, 0, b""
    for block in iter(lambda: p.stdout.read(1 << 20), b""):
        rows += (tail[-(len(key) - 1):] + block).count(key)   # a key cut by the block boundary counts once
        size += len(block)
        tail = (tail + block)[-64:]
    err = p.stderr.read().decode()
    took = time.perf_counter() - t0
    assert p.wait() == 0, err
    peak_mib = int(err.rsplit("peak ", 1)[1]) / 1024
    print(f"kinematics --samples 1000000 --json: {size / 2**30:.2f} GiB in {took:.1f} s, peak {peak_mib:.0f} MiB")
    assert rows == 1_000_000 and tail.endswith(b"\n ]\n}\n")
    assert peak_mib < 400 and took < 300
