"""Every file rigfem writes lands whole or not at all: a writer that fails or is interrupted
mid-file leaves neither the file nor its temporary name (issue 24 §2)."""

from __future__ import annotations

import pandas as pd
import pytest
from matplotlib.animation import PillowWriter

from rigfem.linkage import crank_angles, four_bar, linkage_motion
from rigfem.report.motion import motion_gif
from rigfem.sweep.configs import SweepParams
from rigfem.sweep.report import write_report


def test_sweep_report_interrupted_mid_csv_leaves_nothing(tmp_path, monkeypatch):
    def half_then_interrupt(self, path, *a, **k):
        with open(path, "wb") as fh:
            fh.write(b"b2,b3,half a ro")
        raise KeyboardInterrupt

    monkeypatch.setattr(pd.DataFrame, "to_csv", half_then_interrupt)
    out = tmp_path / "sweep"
    with pytest.raises(KeyboardInterrupt):
        write_report(pd.DataFrame({"b2": [60.0]}), SweepParams(), out)
    assert list(out.iterdir()) == []


def test_gif_interrupted_mid_write_leaves_nothing(tmp_path, monkeypatch):
    def half_then_fail(self):
        with open(self.outfile, "wb") as fh:
            fh.write(b"GIF89a")
        raise KeyboardInterrupt

    monkeypatch.setattr(PillowWriter, "finish", half_then_fail)
    m = linkage_motion(four_bar(200, 500, 400, 600), crank_angles(8), 6.28)
    with pytest.raises(KeyboardInterrupt):
        motion_gif(m, tmp_path / "motion.gif", "test")
    assert list(tmp_path.iterdir()) == []
