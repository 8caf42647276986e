"""A warm check reuses what it derived before, verified: pictures, peak sweeps and the 3-D view's data
are cache entries keyed by everything they come from (issue 26); a changed input draws or computes
again, and a damaged entry is discarded, logged and made again."""

import logging
import re
import shutil

import numpy as np
import pytest

from rigfem.cache import Cache, from_environment
from rigfem.pipeline import Output, Request, run_check
from stages import solved

FAST = {"parts": ["plate_A"], "fidelity": "draft", "samples": 72, "frames": 3, "modes": ["cycle"]}


def _drawer(calls: list):
    def draw(d):
        calls.append(d)
        (d / "a.png").write_bytes(b"picture %d" % len(calls))
        return {"files": {"a": "a.png"}, "renderer": "pyvista"}, ["a.png"]
    return draw


def test_cached_picture_is_copied_changed_inputs_draw_again_and_damage_is_discarded(tmp_path, monkeypatch,
                                                                                     caplog):
    from rigfem.report.picture_cache import cached

    cache = Cache(tmp_path / "cache", 10**9)
    calls = []
    for k in range(3):
        (tmp_path / str(k)).mkdir()
    first = cached("t", {"field": "f1"}, tmp_path / "0", _drawer(calls), cache)
    again = cached("t", {"field": "f1"}, tmp_path / "1", _drawer(calls), cache)
    assert len(calls) == 1 and again == first  # the warm call copied, it did not draw
    assert (tmp_path / "1" / "a.png").read_bytes() == (tmp_path / "0" / "a.png").read_bytes() == b"picture 1"
    cached("t", {"field": "f2"}, tmp_path / "2", _drawer(calls), cache)
    assert len(calls) == 2  # another field: drawn again
    (stored,) = [p for p in (tmp_path / "cache").rglob("pictures/*/a.png")
                 if (p.parent / "result.json").read_text().find("a.png") >= 0 and p.read_bytes() == b"picture 1"]
    stored.write_bytes(b"picture X")  # damaged in the cache
    with caplog.at_level(logging.WARNING, logger="rigfem.cache"):
        cached("t", {"field": "f1"}, tmp_path / "0", _drawer(calls), cache)
    assert len(calls) == 3 and "discarded" in caplog.text  # discarded, drawn again
    assert (tmp_path / "0" / "a.png").read_bytes() == b"picture 3"


def test_fallback_picture_is_not_stored(tmp_path, monkeypatch):
    """A matplotlib fallback (no OpenGL) is drawn every time: a machine with OpenGL draws the real one."""
    from rigfem.report.picture_cache import cached

    cache = Cache(tmp_path / "cache", 10**9)
    calls = []

    def draw(d):
        calls.append(d)
        (d / "a.png").write_bytes(b"fallback")
        return {"renderer": "matplotlib"}, ["a.png"]
    cached("t", {"x": 1}, tmp_path, draw, cache)
    cached("t", {"x": 1}, tmp_path, draw, cache)
    assert len(calls) == 2


@pytest.fixture(scope="module")
def warm(tmp_path_factory):
    """A small check run twice on one cache: the second run may draw, write or encode nothing."""
    import matplotlib.figure
    import PIL.Image

    import rigfem.report.views as views
    import rigfem.report.vtu as vtu

    root = tmp_path_factory.mktemp("warm")
    mp = pytest.MonkeyPatch()
    mp.setenv("RIGFEM_CACHE", str(root / "cache"))
    run_check(Request("final-cm", FAST), Output(root / "cold"))
    drawn = []  # every 3-D render and every matplotlib picture saved
    mp.setattr(views, "render", lambda *a, **k: drawn.append("render"))
    mp.setattr(matplotlib.figure.Figure, "savefig", lambda *a, **k: drawn.append("savefig"))
    mp.setattr(vtu, "write_unstructured", lambda *a, **k: drawn.append("vtu"))  # field files and frames
    mp.setattr(PIL.Image.Image, "save", lambda *a, **k: drawn.append("webp"))  # report.html's pictures
    run_check(Request("final-cm", FAST), Output(root / "warm"))
    yield root, drawn
    mp.undo()


def test_warm_check_copies_every_picture_byte_for_byte(warm):
    root, drawn = warm
    assert drawn == []  # no picture was drawn on the warm run
    cold = sorted(p.name for p in (root / "cold").glob("*.png"))
    assert len(cold) >= 5 and cold == sorted(p.name for p in (root / "warm").glob("*.png"))
    for name in cold:
        assert (root / "warm" / name).read_bytes() == (root / "cold" / name).read_bytes(), name


def test_warm_check_copies_the_field_files_and_the_embedded_pictures(warm):
    """The VTU fields, the animation frames and report.html's WebP pictures: copied, the same bytes."""
    root, drawn = warm
    assert drawn == []
    cold = sorted(p.name for p in (root / "cold").glob("*.vtu"))
    assert any("_cycle_0" in n for n in cold) and cold == sorted(p.name for p in (root / "warm").glob("*.vtu"))
    for name in cold:
        assert (root / "warm" / name).read_bytes() == (root / "cold" / name).read_bytes(), name
    embedded = [re.findall(r"data:image/webp;base64,[A-Za-z0-9+/=]+", (root / d / "report.html").read_text())
                for d in ("cold", "warm")]
    assert len(embedded[0]) >= 5 and embedded[0] == embedded[1]


def test_changed_field_draws_the_part_again(warm, monkeypatch):
    """The same part under another load: its stress field differs, so its pictures are drawn again."""
    import rigfem.report.pictures as pictures
    from rigfem.report.picture_cache import part_pictures

    root, _ = warm
    monkeypatch.setenv("RIGFEM_CACHE", str(root / "cache"))
    _, _, (r,) = solved("final-cm", FAST, whole=True)  # every unit solution: any combination
    drawn = []
    monkeypatch.setattr(pictures, "part_pictures", lambda *a, **k: drawn.append(a) or {"files": {}})
    entry = {"peak_mpa": 37.5, "utilisation_pct": 10.0, "error_pct": 5.0, "verdict": "pass"}
    c = r.coef[r.row]
    (root / "p").mkdir()
    part_pictures(r, c, entry, 100.0, "plate A", "allowable", root / "p")
    part_pictures(r, c, entry, 100.0, "plate A", "allowable", root / "p")
    assert len(drawn) == 1  # the same field: copied
    part_pictures(r, 1.5 * c, entry, 100.0, "plate A", "allowable", root / "p")
    assert len(drawn) == 2  # another field: drawn again


def test_peak_sweep_is_cached_and_a_wrong_stored_peak_is_discarded(warm, monkeypatch, caplog):
    from rigfem.cache import save_arrays
    from rigfem.fe import Solution, peak_sweep

    root, _ = warm
    monkeypatch.setenv("RIGFEM_CACHE", str(root / "cache"))
    cache = from_environment()
    _, _, (r,) = solved("final-cm", FAST, whole=True)  # every unit solution
    sol = r.solution
    assert sol.key  # a cached solution knows its entry
    C = r.coef[::7] * 1.25  # rows no check asked for yet
    ref = Solution.peak_sweep(sol, C)
    vals, nodes = peak_sweep(sol, C, cache)  # computed and stored
    assert np.array_equal(vals, ref[0]) and np.array_equal(nodes, ref[1])
    monkeypatch.setattr(Solution, "peak_sweep", lambda *a: pytest.fail("a stored sweep was computed again"))
    again = peak_sweep(sol, C, cache)
    assert np.array_equal(again[0], vals) and np.array_equal(again[1], nodes)
    inputs = {"solution": sol.key, "C": np.atleast_2d(np.asarray(C, dtype=float))}  # as peak_sweep keys it
    shutil.rmtree(cache.entry_folder("sweeps", inputs))
    cache.put("sweeps", inputs, lambda t: save_arrays(t, {"peak": vals * 0.5, "node": nodes}))  # checksums fine
    monkeypatch.undo()
    monkeypatch.setenv("RIGFEM_CACHE", str(root / "cache"))
    with caplog.at_level(logging.WARNING, logger="rigfem.cache"):
        healed = peak_sweep(sol, C, cache)
    assert "not the stress at its node" in caplog.text
    assert np.array_equal(healed[0], vals)


def test_viewer_data_is_read_once_per_animation(warm, monkeypatch):
    import meshio

    from rigfem.report import viewer

    root, _ = warm
    monkeypatch.setenv("RIGFEM_CACHE", str(root / "cache"))
    d = shutil.copytree(root / "cold", root / "viewer")
    files = [p.name for p in d.iterdir()]
    first = viewer.viewer_data(d, files, 100.0)
    assert first and first[0]["angles"]
    monkeypatch.setattr(meshio, "read", lambda *a, **k: pytest.fail("read the frames again"))
    assert viewer.viewer_data(d, files, 100.0) == first
    monkeypatch.undo()
    monkeypatch.setenv("RIGFEM_CACHE", str(root / "cache"))
    frame = sorted(d.glob("plate_A_cycle_*.vtu"))[0]
    m = meshio.read(frame)
    m.point_data["von_mises"] = 2 * m.point_data["von_mises"]
    meshio.write(frame, m)  # another frame: read again
    assert viewer.viewer_data(d, files, 100.0) != first


def test_the_3d_views_triangles_take_two_bytes_where_their_indices_fit(warm):
    """The page carries each triangle's vertex indices in 2 bytes when the part has at most 65536 surface
    vertices (every built-in part): the same triangles, half the bytes."""
    import base64

    from rigfem.report import viewer

    root, _ = warm
    d = root / "cold"
    parts = viewer.viewer_data(d, [p.name for p in d.iterdir()], 100.0)
    assert parts
    for p in parts:
        assert p["tri_bytes"] == 2 and p["vertices"] <= 2**16
        tri = np.frombuffer(base64.b64decode(p["tri"]), "<u2")
        assert tri.size % 3 == 0 and tri.max() == p["vertices"] - 1 and np.unique(tri).size == p["vertices"]
