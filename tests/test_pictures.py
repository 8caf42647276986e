"""Pictures that cannot mislead (issue 40 §2): a long part fills its view, every label is readable
(no two overlap, none leaves the figure), every support is drawn and named, the part frame's axes
are shown, and utilisation has one colour map, defined once, in every picture and page."""

import re
from pathlib import Path

import numpy as np
import pytest

from rigfem.report import scale

PKG = Path(__file__).resolve().parents[1] / "rigfem"


def _bar_mesh(length=480.0, width=25.0, height=20.0, n=(48, 4, 4)):
    """Tetrahedra of a box (each hexahedron split in six): a stand-in for a rail."""
    xs, ys, zs = (np.linspace(0, d, k + 1) for d, k in zip((length, width, height), n))
    pts = np.stack(np.meshgrid(xs, ys, zs, indexing="ij"), -1).reshape(-1, 3)
    idx = np.arange(len(pts)).reshape(n[0] + 1, n[1] + 1, n[2] + 1)
    c = [idx[i:i + n[0], j:j + n[1], k:k + n[2]].ravel() for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    # corners c[ijk]: 0=000 1=001 2=010 3=011 4=100 5=101 6=110 7=111; the six tets of the main diagonal 0-7
    tets = np.concatenate([np.stack([c[0], c[a], c[b], c[7]], 1)
                           for a, b in ((4, 6), (6, 2), (2, 3), (3, 1), (1, 5), (5, 4))])
    return pts, tets


@pytest.fixture(scope="module")
def rail_view():
    """A crowded long part: the peak on a held hole, both extremes and two loads near one end."""
    pytest.importorskip("pyvista")
    from rigfem.report.views import FieldView, framing

    pts, tets = _bar_mesh()
    values = 100 * np.exp(-((pts[:, 0] - 60) / 60) ** 2)
    hi = int(np.argmax(values))
    from rigfem.mesh.partmesh import boundary_faces

    faces = boundary_faces(tets)
    top, mid = (pts[faces][..., 2] == 20.0).all(1), pts[faces].mean(1)
    held = [(faces[top & (np.hypot(mid[:, 0] - x, mid[:, 1] - 12.5) < 12)], f"held: hole_0{k}")
            for k, x in enumerate((20.0, 60.0))]
    assert all(len(t) for t, _ in held)
    view = FieldView(points=pts, tets=tets, values=values, clim=scale.UTILISATION_SCALE_PCT, cmap=scale.colormap(),
                     above=scale.ABOVE_COLOUR,
                     marks=[(pts[hi], "max 144.5 MPa (38.5 %)"), (pts[-1], "min 0.0067 MPa")], supports=held,
                     arrows=[(np.array([440.0, 12.5, 20.0]), np.array([294.0, 0, -50]), "hole_09: 294 N"),
                             (np.array([470.0, 12.5, 20.0]), np.array([294.0, 0, -50]), "hole_11: 294 N")])
    d, up, elongated = framing(pts, pts[hi], np.array([0.0, 0.0, 1.0]))
    return view, d, up, elongated


def _filled(img: np.ndarray) -> tuple[float, float]:
    """Fraction of the image's width and height that the drawn (not white) pixels span."""
    ink = np.argwhere((img < 245).any(-1))
    (r0, c0), (r1, c1) = ink.min(0), ink.max(0)
    return (c1 - c0 + 1) / img.shape[1], (r1 - r0 + 1) / img.shape[0]


def test_a_long_part_fills_its_view(rail_view):
    from rigfem.report.views import render

    view, d, up, elongated = rail_view
    assert elongated
    whole = render(view, (1560, 300), d, up, shrink=True)
    w, h = _filled(whole.image)
    assert w > 0.85 and h > 0.6, (w, h)  # not a sliver in a tall picture (10 % of its height before)
    i, j = (int(round(v)) for v in whole.pixel(view.points[np.argmax(view.values)]))
    assert 0 <= i < whole.image.shape[1] and 0 <= j < whole.image.shape[0]  # the projection finds the peak


def test_labels_do_not_overlap_and_stay_in_the_picture(rail_view, tmp_path):
    from rigfem.report.pictures import _BOTTOM, _GAP, _TOP, _page
    from rigfem.report.views import render

    view, d, up, _ = rail_view
    whole = render(view, (1560, 300), d, up, shrink=True)
    peak = view.points[np.argmax(view.values)]
    close = render(view, (980, _TOP - 2 * _GAP - whole.image.shape[0] - _BOTTOM), d, up, (peak - 30, peak + 30),
                   shrink=True)
    texts = [t for _, _, t, _ in whole.labels]
    assert set(texts) == {"max 144.5 MPa (38.5 %)", "min 0.0067 MPa", "held: hole_00", "held: hole_01",
                          "hole_09: 294 N", "hole_11: 294 N"}  # every support named, the one at the peak too
    boxes = _page([whole, close], True, ["title", "line"], "pass", "legend", tmp_path / "p.png",
                  lambda fig: None, (whole.right, whole.up, d))
    assert len(boxes) == len(whole.labels) + len(close.labels)
    for k, (ta, a) in enumerate(boxes):
        assert a.x0 >= 0 and a.y0 >= 0 and a.x1 <= 1600 and a.y1 <= 1000, (ta, a)  # inside the figure
        for tb, b in boxes[k + 1:]:
            assert not a.overlaps(b), (ta, tb)


def test_the_triad_shows_the_part_frame_as_the_view_does():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rigfem.report.pictures import triad

    fig = plt.figure()
    triad(fig, [0.1, 0.1, 0.3, 0.3], np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), np.array([0, -1.0, 0]))
    texts = {t.get_text(): t.get_position() for t in fig.axes[0].texts}
    plt.close(fig)
    assert texts["x"][0] > 1 and abs(texts["x"][1]) < 1e-9  # x to the right
    assert texts["z"][1] > 1  # z up
    assert "y (away)" in texts  # y along the line of sight, away from the viewer


def test_one_colour_map_for_utilisation_defined_once():
    import matplotlib

    cm = matplotlib.colormaps[scale.UTILISATION_CMAP]
    assert scale.UTILISATION_STOPS == [[round(255 * v) for v in cm(i / 10)[:3]] for i in range(11)]
    offenders = []
    for f in PKG.rglob("*"):
        if f.suffix not in (".py", ".js", ".j2") or f.name == "scale.py":
            continue
        text = f.read_text()
        for pat in (r"turbo|viridis|RdYlGn|jet\b|cmap\s*=\s*[\"']", r"\[68,\s*1,\s*84\]", r"rgb\(\s*230,\s*0,\s*200"):
            offenders += [f"{f.relative_to(PKG)}: {m.group(0)}" for m in re.finditer(pat, text)]
    assert offenders == [], offenders  # every picture and page takes its colours from rigfem.report.scale
    for page in ("report.html.j2", "explorer.html.j2"):
        assert 'id="util-scale">{{ utilisation_scale }}' in (PKG / "templates" / page).read_text()


def test_the_animation_holds_the_governing_crank_angle_of_every_cycle_case():
    from types import SimpleNamespace

    from rigfem.fe.partcase import frame_rows

    for row in (8, 0, 359, 123):
        r = SimpleNamespace(mode="cycle", row=row, case=SimpleNamespace(rows=np.arange(360.0)))
        rows = frame_rows(r, 12)
        assert row in rows and len(rows) in (12, 13) and rows == sorted(rows)
    assert frame_rows(SimpleNamespace(mode="original", row=8, case=SimpleNamespace(rows=np.arange(1.0))), 12) == []
    assert frame_rows(SimpleNamespace(mode="cycle", row=8, case=SimpleNamespace(rows=np.arange(360.0))), 0) == []


def test_the_quick_return_motion_plot_has_no_empty_panel_nor_curves_on_top_of_each_other(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rigfem import linkage
    from rigfem.linkage.mechanisms import quick_return
    from rigfem.report import motion

    lk = quick_return(150.0, 350.0, 800.0)  # results/kinematics/mech4-quick-return.png's linkage
    m = linkage.linkage_motion(lk, linkage.crank_angles(360), 10.0, 0.0)
    groups = motion.same_rotation(m)
    assert sum(len(g) for g in groups) == len(m.links) - 1 and len(groups) < len(m.links) - 1
    drawn = []
    real = plt.subplots

    def spy(*a, **k):
        fig, axs = real(*a, **k)
        drawn.append((fig, axs))
        return fig, axs

    patch = pytest.MonkeyPatch()
    patch.setattr(plt, "subplots", spy)
    try:
        motion.motion_plot(m, tmp_path / "qr.png", "quick-return")
    finally:
        patch.undo()
    (fig, axs), = drawn
    for ax in axs.flat:
        assert ax.lines, ax  # no empty panel
        ys = [tuple(np.round(np.asarray(line.get_ydata(), float), 9)) for line in ax.lines]
        assert len(set(ys)) == len(ys)  # no two identical curves on top of each other


def test_a_free_body_legend_stays_in_the_picture(tmp_path):
    """A cycle-mode rail's legend (a free body: the longest support text) ran past the right edge of the
    picture beside the rail's close-up: its lines are wrapped, and drawn where _page puts it they end inside."""
    import matplotlib.pyplot as plt

    from rigfem.report.pictures import LEGEND_CHARS, legend_text

    text = legend_text(True, "free body in dynamic equilibrium (inertia relief), no support")
    assert max(len(line) for line in text.split("\n")) <= LEGEND_CHARS and "inertia relief" in text
    fig = plt.figure(figsize=(16, 10), dpi=100)
    t = fig.text((20 + 980 + 30) / 1600, 185 / 1000, text, fontsize=13, va="bottom")  # _page's place beside a rail
    fig.canvas.draw()
    box = t.get_window_extent(fig.canvas.get_renderer())
    plt.close(fig)
    assert box.x1 <= 1600 and box.y1 <= 300, box  # inside, and under the triad's lowest text (≈ 320 px up)


def test_save_png_draws_the_pixels_savefig_would(tmp_path):
    """save_png draws the figure once and encodes it once (RGB): the pixels of ``savefig`` at the same
    dpi, to antialiasing rounding (a wrong dpi or a channel order mix-up fails)."""
    import matplotlib.pyplot as plt
    from PIL import Image

    from rigfem.report.pictures import save_png

    fig = plt.figure(figsize=(4, 3))
    fig.text(0.05, 0.9, "allowable σu/2 = 375 MPa", fontsize=14, color="#d32f2f")
    ax = fig.add_axes([0.15, 0.15, 0.8, 0.6])
    ax.plot([0, 1, 2], [0, 2, 1], color="#1565c0")
    fig.savefig(tmp_path / "savefig.png", dpi=110)
    save_png(fig, tmp_path / "ours.png", dpi=110)
    plt.close(fig)
    with Image.open(tmp_path / "savefig.png") as a, Image.open(tmp_path / "ours.png") as b:
        assert b.mode == "RGB" and b.size == a.size == (440, 330)
        diff = np.abs(np.asarray(a.convert("RGB"), int) - np.asarray(b, int))
    assert diff.max() <= 1
