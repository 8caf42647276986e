"""A cold report's part pictures are drawn in child processes while the check writes its field
files (issue 26): the same pictures as drawing them in the check's own process."""

import multiprocessing as mp
import time

import pytest

from rigfem.cache import from_environment
from stages import solved

FAST = {"parts": ["plate_A", "plate_B"], "fidelity": "draft", "samples": 72, "frames": 0, "modes": ["cycle"]}


@pytest.fixture(scope="module")
def results():
    return solved("final-cm", FAST)[2]


@pytest.mark.heavy  # over 8 s: the default run stays under 10 minutes (CI's heavy stage runs it)
def test_pictures_drawn_in_child_processes_are_the_ones_drawn_here(results, tmp_path, monkeypatch):
    """A cold report's part pictures are drawn in two children from a copy of each result that
    holds only its critical combination: the same files, byte for byte, and the same result as
    drawing from the whole result in this process; a picture the cache holds is only copied."""
    import rigfem.report.picture_cache as pc

    entry = {"peak_mpa": 37.5, "utilisation_pct": 10.0, "error_pct": 5.0, "verdict": "pass"}
    jobs = {d: [(r, r.coef[r.row], entry, 375.0, r.case.name, "allowable", tmp_path / d) for r in results]
            for d in ("here", "children", "copied")}
    for d in jobs:
        (tmp_path / d).mkdir()
    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path / "c1"))
    here = [pc.part_pictures(*job) for job in jobs["here"]]
    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path / "c2"))

    def not_here(*a, **k):
        raise AssertionError("drawn in this process")

    monkeypatch.setattr(pc, "part_pictures", not_here)  # the children import their own
    with pc.started_part_pictures(jobs["children"], from_environment()) as wait:
        children = wait()
    assert children == here and len(children) == 2
    names = sorted(p.name for p in (tmp_path / "here").iterdir())
    assert len(names) == 6 and names == sorted(p.name for p in (tmp_path / "children").iterdir())
    for name in names:
        assert (tmp_path / "children" / name).read_bytes() == (tmp_path / "here" / name).read_bytes(), name
    monkeypatch.setattr("rigfem.mesh.worker.call", not_here)
    with pc.started_part_pictures(jobs["copied"], from_environment()) as wait:  # warm: copied, no child started
        assert wait() == here
    assert sorted(p.name for p in (tmp_path / "copied").iterdir()) == names


def test_an_error_while_they_draw_ends_the_children_first(results, tmp_path, monkeypatch):
    """The check fails while the children draw: they are ended before the error goes on, so no
    child outlives it to write into a folder the caller is about to remove."""
    import rigfem.report.picture_cache as pc

    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path / "cache"))
    entry = {"peak_mpa": 37.5, "utilisation_pct": 10.0, "error_pct": 5.0, "verdict": "pass"}
    jobs = [(r, r.coef[r.row], entry, 375.0, r.case.name, "allowable", tmp_path) for r in results]
    def drawing() -> int:
        return len([p for p in mp.active_children() if p.name == "rigfem-pictures"])

    with pytest.raises(RuntimeError, match="stop"):
        with pc.started_part_pictures(jobs, from_environment()):
            t0 = time.monotonic()
            while drawing() < 2 and time.monotonic() - t0 < 30:  # both children have started
                time.sleep(0.01)
            assert drawing() == 2
            raise RuntimeError("stop")
    assert drawing() == 0
