"""The sweep on a real distributed Dask cluster: a scheduler and two worker processes started with
Dask's own command-line programs (``dask scheduler`` / ``dask worker``), bound to 127.0.0.1."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest
from test_sweep import CHECK, CONFIGS

from rigfem.cache import Cache
from rigfem.context import Context
from rigfem.sweep import SweepOptions, SweepParams, build_bases, run_sweep

DASK = shutil.which("dask", path=str(Path(sys.executable).parent)) or shutil.which("dask")


def _stop(proc: subprocess.Popen) -> None:
    """End a process group this test started (the worker's nanny and its worker process)."""
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=15)


@pytest.fixture
def dask_cluster(tmp_path):
    """``tcp://127.0.0.1:PORT`` of a scheduler with two single-thread workers; always torn down."""
    from dask.distributed import Client

    assert DASK is not None, "the dask program (dask[distributed], a declared dependency) is not installed"
    sched_file, procs = tmp_path / "scheduler.json", []
    log = open(tmp_path / "dask.log", "w")

    def start(*args: str) -> None:
        procs.append(subprocess.Popen([DASK, *args], cwd=tmp_path, stdout=log, stderr=subprocess.STDOUT,
                                      start_new_session=True))

    try:
        start("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard", "--scheduler-file", str(sched_file))
        t0 = time.monotonic()
        while not sched_file.is_file() or not sched_file.read_text().strip():
            if procs[0].poll() is not None or time.monotonic() - t0 > 60:
                pytest.fail(f"dask scheduler did not start: {(tmp_path / 'dask.log').read_text()[-2000:]}")
            time.sleep(0.2)
        address = json.loads(sched_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        for i in range(2):
            start("worker", "--scheduler-file", str(sched_file), "--nworkers", "1", "--nthreads", "1",
                  "--host", "127.0.0.1", "--no-dashboard", "--name", f"w{i}",
                  "--local-directory", str(tmp_path / f"w{i}"))
        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=120)
        yield address
    finally:
        for p in reversed(procs):
            _stop(p)
        log.close()


@pytest.mark.heavy
def test_sweep_on_cli_started_cluster_equals_serial(dask_cluster, tmp_path):
    from dask.distributed import Client

    params = SweepParams(check=CHECK)
    bases = build_bases(params)
    serial = run_sweep(params, Context(Cache(tmp_path / "serial", 10**9)),
                       SweepOptions(2, configs=tuple(CONFIGS), bases=bases))
    dist = run_sweep(params, Context(Cache(tmp_path / "dask", 10**9)),
                     SweepOptions(2, dask_cluster, configs=tuple(CONFIGS), bases=bases))
    pd.testing.assert_frame_equal(serial, dist)
    with Client(dask_cluster) as client:  # the chunks ran in the two worker processes, not here
        pids = client.run(os.getpid)
        done = client.run(lambda dask_worker: dask_worker.state.executed_count)
    assert len(set(pids.values())) == 2 and os.getpid() not in pids.values()
    assert sum(done.values()) >= 3  # three chunks of two configurations
