"""Scripts written against the public names before 0.1 still run, with a DeprecationWarning each.

The script is README's "Your own part" example as it was (``git show 98e8437^:examples/solve_part.py``),
plus the presets' mapping access of that time (``FIDELITY["standard"]["order"]``).
"""

import subprocess
import sys

import pytest

OLD_SCRIPT = '''
import warnings
warnings.simplefilter("always", DeprecationWarning)
from rigfem.fe import BearingLoad, ShaftInHole, build_model, solve
from rigfem.material import get_material
from rigfem.mesh import MeshSettings, mesh_part
from rigfem.rig import load_part
from rigfem.settings import FIDELITY
from rigfem.verdict import half_ultimate

steel = get_material("rig_steel")
plate = load_part("PF_4b_006")
pm = mesh_part(plate, MeshSettings(size=6.0, refine=("bore", "screw_1", "screw_2"), refine_size=1.2))
model = build_model(pm, steel, order=FIDELITY["standard"]["order"])
supports = [ShaftInHole("screw_1"), ShaftInHole("screw_2")]
sol = solve(model, supports, [BearingLoad("bore", (2000.0, 0.0, 0.0))])  # N, along x
peak = sol.peak()
v = half_ultimate(peak.value, steel.sigma_u, 100 * peak.error)
print(f"{len(pm.points)} nodes; peak von Mises {peak.value:.1f} MPa ± {100 * peak.error:.1f} % "
      f"on '{peak.surface}' at {[round(float(t), 1) for t in peak.xyz]} mm")
print(f"{v.utilisation_pct:.1f} % of σu/2 = {v.limit_mpa:.0f} MPa: {v.verdict}")
'''


def test_a_script_of_the_old_names_runs_with_warnings():
    """MeshSettings(size=, refine_size=), FIDELITY[name][field] and Peak.error: the same numbers
    as the new names, each with a DeprecationWarning naming its replacement."""
    out = subprocess.run([sys.executable, "-c", OLD_SCRIPT], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert "peak von Mises" in out.stdout and "of σu/2" in out.stdout
    for needle in ("MeshSettings(size=...) is deprecated, use size_mm=",
                   "MeshSettings(refine_size=...) is deprecated, use local_size_mm=",
                   "preset['order'] is deprecated, use preset.order",
                   "Peak.error is deprecated, use Peak.zz_error"):
        assert needle in out.stderr, needle


def test_old_names_mean_the_new_ones():
    """Each alias resolves to the field it was renamed to."""
    import warnings

    from rigfem.fe.solution import Peak
    from rigfem.settings import FIDELITY, MeshSettings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        assert MeshSettings(size=6.0, refine_size=1.2, refine_dist=9.0) == MeshSettings(6.0, (), 1.2, 9.0)
        assert [FIDELITY["fine"][k] for k in ("order", "size_mm", "local_size_mm", "bearing_directions")] == [2, 4.0, 0.6, 12]
        assert Peak(1.0, 0, (0.0, 0.0, 0.0), "hole", ("hole",), 0.03, 4.5).error == 0.03


def test_run_sweep_in_its_form_before_0_2_runs_with_a_warning(monkeypatch, tmp_path):
    """``run_sweep(p, work_dir, chunk_size=..., workers=..., scheduler=...)`` (docs before 0.2) maps to a
    Context and SweepOptions, warning; an unknown keyword is still a TypeError."""
    from rigfem.context import Context
    from rigfem.sweep import run as sweep_run

    monkeypatch.setenv("RIGFEM_CACHE", str(tmp_path / "cache"))
    with pytest.warns(DeprecationWarning, match="run_sweep.p, work_dir"):
        ctx, opts = sweep_run.old_call(str(tmp_path / ".work"), {"chunk_size": 8, "workers": 2, "configs": [{"a": 1}],
                                                                 "scheduler": None, "progress": False})
    assert isinstance(ctx, Context) and ctx.workers == 2 and ctx.cache.root == tmp_path / "cache"
    assert (opts.chunk_size, opts.configs, opts.scheduler) == (8, ({"a": 1},), None)
    with pytest.warns(DeprecationWarning), pytest.raises(TypeError, match="work_folder"):
        sweep_run.old_call("w", {"work_folder": "x"})
