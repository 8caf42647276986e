"""Plant each of a fixed set of physics bugs in a scratch copy of rigfem and check a test fails.

    python tools/physics_mutations.py                 # every mutation; writes results/mutation/physics_mutations.json
    python tools/physics_mutations.py --only e_x2 zz_x0.25 --no-record
    python tools/physics_mutations.py --list

Each mutation (:data:`MUTATIONS`) is a name, a file, an exact code snippet, its replacement and the
tests expected to catch it (fast ones against independent truths).  The work tree is copied once
to a scratch folder; for each mutation the snippet must occur in its file exactly once (else the
script fails: a refactor moved the code, so the mutation must be moved with it), it is replaced,
the named tests run there (``pytest -x``, ``PYTHONPATH`` at the copy, no bytecode) and the file is
restored.  Every mutation gets a fresh rigfem cache holding only the unmutated run's meshes:
rigfem keys its meshes, solutions and everything derived by a hash of the code that computes them
(``rigfem.mesh.cache.code_hash``), so a cached solution cannot hide a mutation, but a fresh cache
does not rely on that.  Before the mutations the named tests run unmutated and must pass.

A mutation is *killed* when a named test fails (pytest exit 1 or 2, a collection error); it
*survives* when they all pass.  The script exits 1 if any survives and writes the record
(``results/mutation/physics_mutations.json`` and ``.md``: date, commit, dirty flag, machine,
command, per mutation the tests, the first that failed and the time).  ``tests/test_physics_mutations.py``
(``heavy``: CI's ``pytest -m heavy``) runs it.
"""

from __future__ import annotations

import argparse
import datetime
import importlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from dataclasses import asdict, dataclass, replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "results" / "mutation"
sys.path.insert(0, str(ROOT / "benchmarks"))
record = importlib.import_module("record")  # benchmarks/record.py, a sibling script: machine(), commit(), command_line()

T = "tests/test_physics_truths.py::"
REF = "tests/test_reference_scenes.py::test_final_cm_parts_reproduce_their_committed_figures"
LOADS = T + "test_original_load_case_is_the_studys"
NEWTON = T + "test_rig_fourbar_reactions_are_the_newton_euler_solution"


@dataclass(frozen=True)
class Mutation:
    name: str
    file: str  #: relative to the repository
    snippet: str  #: exact text, found exactly once in the file
    replacement: str
    tests: tuple[str, ...]  #: pytest node ids expected to catch it, fastest first
    what: str  #: the bug, in words


MUTATIONS = (
    # --- the minimum set -----------------------------------------------------------------
    Mutation("load_factor_x1.25", "rigfem/loads/cases.py",
             "original_rail(h, pk, bar, settings.load_factor)", "original_rail(h, pk, bar, 1.25 * settings.load_factor)",
             (LOADS, f"{REF}[crank_rail]"), "original-mode rail loads 25 % above the study's 1.4 × peak reaction"),
    Mutation("plate_loads_x2", "rigfem/loads/cases.py",
             "_one_per_row(len(dirs), 1, factor * mag)", "_one_per_row(len(dirs), 1, 2 * factor * mag)",
             (LOADS, f"{REF}[plates]"), "every plate's original-mode load doubled"),
    Mutation("plate_cycle_loads_x2", "rigfem/loads/cases.py",
             'loads, coef = bearing_cases({"bore": f}, n_dir)', 'loads, coef = bearing_cases({"bore": 2 * f}, n_dir)',
             (T + "test_cycle_bearing_weights_rebuild_the_pin_force_at_every_angle", f"{REF}[plates]"),
             "every plate's cycle-mode load doubled"),
    Mutation("stress_x0.8", "rigfem/fe/stress.py",
             "s[:, :, v] = tr + 2 * mu * H[:, :, i, i] if i == j else mu * (H[:, :, i, j] + H[:, :, j, i])",
             "s[:, :, v] = 0.8 * (tr + 2 * mu * H[:, :, i, i] if i == j else mu * (H[:, :, i, j] + H[:, :, j, i]))",
             ("tests/test_fe_cantilever.py::test_root_bending_stress", f"{REF}[plates]"),
             "every stress from the displacements 20 % low"),
    Mutation("zz_x0.25", "rigfem/fe/stress.py",
             "return float(von_mises(Se - s_patch[local]).max() / ref) if ref > 0 else 0.0",
             "return 0.25 * float(von_mises(Se - s_patch[local]).max() / ref) if ref > 0 else 0.0",
             (T + "test_error_band_covers_the_hole_peak_on_coarse_meshes", f"{REF}[plates]"),
             "the ZZ error estimate four times too small (bands four times too narrow)"),
    Mutation("e_x2", "rigfem/material.py",
             '"rig_steel": Material("rig_steel", 210000.0, 0.3, 750.0, 7.85e-9)',
             '"rig_steel": Material("rig_steel", 420000.0, 0.3, 750.0, 7.85e-9)',
             (T + "test_rig_steel_is_the_studys_steel", T + "test_a_steel_cantilever_bends_as_beam_theory",
              f"{REF}[plates]"), "the rig steel's Young's modulus doubled"),
    Mutation("e_x2_in_stiffness", "rigfem/fe/model.py", "stiffness(self.mesh, self.material.E, self.material.nu)",
             "stiffness(self.mesh, 2 * self.material.E, self.material.nu)",
             (T + "test_a_steel_cantilever_bends_as_beam_theory", f"{REF}[plates]"),
             "the stiffness assembled with twice E (stresses unchanged where statically determinate)"),
    Mutation("bearing_direction_dropped", "rigfem/loads/cases.py",
             "np.add.at(w, (rows, k1), np.maximum(b, 0.0))",
             "np.add.at(w, (rows, k1), np.maximum(b, 0.0) * (k1 != n_dir - 1))",
             ("tests/test_loadcases.py::test_direction_weights_reproduce_vector_and_stay_nonnegative",
              T + "test_cycle_bearing_weights_rebuild_the_pin_force_at_every_angle"),
             "the last of the bearing directions never gets a weight (forces between it and 0° lose a part)"),
    Mutation("support_released", "rigfem/loads/cases.py",
             "pivot = tuple(rail_hole_name(i) for i in bar.layout.coupling(0.0, bar.name))",
             "pivot = tuple(rail_hole_name(i) for i in bar.layout.coupling(0.0, bar.name))[:1]",
             (LOADS, f"{REF}[crank_rail]"), "a rail held by one screw of its pivot coupling instead of two"),
    Mutation("gravity_sign_dynamics", "rigfem/dynamics/forces.py",
             "f = body.mass_kg * (gravity - body.com_acc)", "f = body.mass_kg * (-gravity - body.com_acc)",
             (T + "test_the_frame_carries_the_linkage_weight_at_rest", NEWTON), "gravity pulls the linkage up"),
    Mutation("gravity_sign_fe", "rigfem/fe/forces.py",
             'return np.r_[_vec("Gravity.g", load.g), np.zeros(9)]', 'return np.r_[-_vec("Gravity.g", load.g), np.zeros(9)]',
             (T + "test_a_beam_sags_under_its_own_weight",), "the FE gravity load points up"),
    Mutation("crank_speed_x2", "rigfem/linkage/state.py",
             "closed_motion(lk, np.radians(deg), 2 * np.pi * speed_hz)", "closed_motion(lk, np.radians(deg), 4 * np.pi * speed_hz)",
             (NEWTON, "tests/test_original.py::test_original_program_matches_calibration"),
             "the crank turns twice as fast as the scene says"),
    # --- more: loads, dynamics, FE, verdict, mesh ---------------------------------------------------
    Mutation("point_mass_inertia_sign", "rigfem/loads/cases.py",
             "f -= m * _point_acc(b, np.asarray(local, float)) / 1000.0", "f += m * _point_acc(b, np.asarray(local, float)) / 1000.0",
             ("tests/test_loadcases.py::test_cycle_rail_loads_balance_the_rigid_body_dynamics", f"{REF}[crank_rail]"),
             "a coupling's point masses push the rail along their acceleration instead of against it"),
    Mutation("driver_torque_couple_flipped", "rigfem/loads/cases.py",
             "return half - couple, half + couple", "return half + couple, half - couple",
             ("tests/test_loadcases.py::test_cycle_rail_loads_balance_the_rigid_body_dynamics", f"{REF}[crank_rail]"),
             "the motor torque enters the crank as a couple of the wrong sense"),
    Mutation("rail_inertia_omega_sign", "rigfem/loads/cases.py",
             "b.alpha_rad_s2[:, None], (b.omega_rad_s ** 2)[:, None]]", "b.alpha_rad_s2[:, None], -(b.omega_rad_s ** 2)[:, None]]",
             ("tests/test_loadcases.py::test_cycle_rail_loads_balance_the_rigid_body_dynamics", f"{REF}[crank_rail]"),
             "the rail's centripetal inertia points outwards"),
    Mutation("far_load_on_one_screw", "rigfem/loads/cases.py", "    f = factor * mag / 2\n", "    f = factor * mag\n",
             (LOADS, f"{REF}[crank_rail]"), "the original-mode rail load applied in full at each of the two far screws"),
    Mutation("post_loads_halved", "rigfem/loads/cases.py",
             "iprofile_screw_load_n: tuple[float, float] = (250.0, 250.0)", "iprofile_screw_load_n: tuple[float, float] = (125.0, 125.0)",
             (LOADS, f"{REF}[post_B]"), "the post's study load halved"),
    Mutation("rail_mass_study_value", "rigfem/rig/catalogue.py", "rail_kg_m: float = 3.1", "rail_kg_m: float = 2.7",
             (NEWTON, "tests/test_loadcases.py::test_dynamics_rail_matches_the_meshed_rail"),
             "the rigid-body model's rails weigh the study's 2.7 kg/m instead of the catalogue's 3.1"),
    Mutation("rail_inertia_about_end", "rigfem/linkage/mechanisms.py", "m * length_mm**2 / 12", "m * length_mm**2 / 3",
             (NEWTON,), "a rail's moment of inertia taken about its end instead of its centre"),
    Mutation("original_model_quirk_dropped", "rigfem/dynamics/original.py",
             "ra, rb = -L3 / 2 * u3, (b3 - L3 / 2) * u3", "ra, rb = -b3 / 2 * u3, (b3 - b3 / 2) * u3",
             ("tests/test_original.py::test_original_program_matches_calibration",),
             "the 2013 program's lever arm L3/2 replaced by b3/2 (no longer the study's program)"),
    Mutation("peak_not_refined", "rigfem/dynamics/history.py",
             "if toggle is None and refine and ev is not None and step > 0.0:",
             "if toggle is None and not refine and ev is not None and step > 0.0:",
             (T + "test_peak_reactions_are_the_largest_newton_euler_forces",),
             "peak reactions read off the samples instead of refined between them"),
    Mutation("von_mises_shear", "rigfem/tensors.py", "+ 3 * (xy ** 2 + yz ** 2 + xz ** 2)", "+ (xy ** 2 + yz ** 2 + xz ** 2)",
             ("tests/test_verdict.py::test_von_mises_uniaxial_and_shear",), "von Mises without the factor 3 on shear"),
    Mutation("lame_mu", "rigfem/material.py", "E / (2 * (1 + nu))", "E / (2 * (1 + 2 * nu))",
             (T + "test_a_steel_cantilever_bends_as_beam_theory", "tests/test_fe_closed_form.py::test_lame_thick_walled_cylinder"),
             "the shear modulus from a wrong formula"),
    Mutation("bearing_pressure_wrong_half", "rigfem/fe/forces.py", "w = np.maximum(r @ d, 0.0)", "w = np.maximum(-(r @ d), 0.0)",
             ("tests/test_fe_loads.py::test_bearing_load_resultant_equals_force", f"{REF}[plates]"),
             "a pin pulls on the far half of its hole instead of pushing on the near half"),
    Mutation("inertia_body_force_sign", "rigfem/fe/forces.py",
             "return -np.r_[a0 + M @ (centroid - o), M.ravel()]", "return np.r_[a0 + M @ (centroid - o), M.ravel()]",
             ("tests/test_fe_freebody.py::test_bar_with_inertia_balanced_by_joint_forces", f"{REF}[crank_rail]"),
             "the d'Alembert body force along the acceleration"),
    Mutation("shaft_foundation_soft", "rigfem/fe/supports.py",
             "kr = E / hole.radius if s.k_radial is None else s.k_radial",
             "kr = 0.01 * E / hole.radius if s.k_radial is None else s.k_radial",
             (f"{REF}[plates]",), "screws and shafts 100 times softer in their holes"),
    Mutation("band_factor_p2_halved", "rigfem/fe/stress.py", "BAND_FACTOR = {1: 2.05, 2: 1.0}", "BAND_FACTOR = {1: 2.05, 2: 0.5}",
             ("tests/test_band_coverage.py::test_committed_record_sets_the_factors_and_every_preset_covers_95_percent",
              T + "test_error_band_covers_the_hole_peak_on_coarse_meshes"),
             "P2 error bands half as wide as their calibration"),
    Mutation("limit_sigma_u", "rigfem/verdict/criterion.py",
             "return factor * sigma_u_mpa", "return sigma_u_mpa",
             ("tests/test_verdict.py::test_half_ultimate_pass_fail_undecided",), "the allowable is σu instead of σu/2"),
    Mutation("straddling_band_passes", "rigfem/verdict/criterion.py",
             'verdict = "pass" if hi < limit else', 'verdict = "pass" if peak < limit else',
             ("tests/test_verdict.py::test_half_ultimate_pass_fail_undecided",),
             "a peak whose band straddles the limit passes instead of being undecided"),
    Mutation("imbalance_tolerated", "rigfem/verdict/criterion.py", "IMBALANCE_TOL = 0.05", "IMBALANCE_TOL = 0.5",
             ("tests/test_verdict_truths.py::test_a_free_body_out_of_balance_by_more_than_five_percent_is_undecided",
              "tests/test_trust.py::test_criterion_never_passes_unloaded_or_unbalanced"),
             "a free body 50 % out of balance still gets a verdict"),
    Mutation("endurance_limit", "rigfem/verdict/fatigue.py", "se_prime = 0.5 * su", "se_prime = 0.6 * su",
             ("tests/test_verdict.py::test_marin_shigley_worked_values",), "Se' = 0.6 Sut instead of 0.5 Sut"),
    Mutation("local_size_ignored", "rigfem/settings.py",
             "return self.local_size_mm if self.local_size_mm is not None else self.size_mm / 4", "return self.size_mm",
             (f"{REF}[plates]",), "no local refinement at the loaded holes"),
)


def scratch_copy(dest: Path) -> None:
    """The work tree as it is (tracked files with their edits, and new files not ignored) at ``dest``."""
    if dest.exists():
        shutil.rmtree(dest)
    files = subprocess.run(["git", "-C", str(ROOT), "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                           capture_output=True, text=True, check=True).stdout.split("\0")
    for f in filter(None, files):
        src = ROOT / f
        if not (src.exists() or src.is_symlink()):
            continue  # deleted in the work tree
        (dest / f).parent.mkdir(parents=True, exist_ok=True)
        if src.is_symlink():
            os.symlink(os.readlink(src), dest / f)
        else:
            shutil.copy2(src, dest / f)


def check_snippets(mutations=MUTATIONS, root: Path = ROOT) -> list[str]:
    """Why a mutation cannot be applied (its snippet not exactly once in its file), one line each."""
    out = []
    for m in mutations:
        n = (root / m.file).read_text().count(m.snippet) if (root / m.file).exists() else -1
        if n != 1:
            out.append(f"{m.name}: {m.file} holds its snippet {n} times (must be exactly once): {m.snippet!r}"
                       if n >= 0 else f"{m.name}: no file {m.file}")
    return out


def run_tests(copy: Path, tests, cache: Path, junit: Path, timeout_s: float) -> tuple[int, list[str], float]:
    """pytest on ``tests`` in the copy: exit code, the failed test ids, wall seconds."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "RIGFEM_CACHE", "CI")}
    env.update(PYTHONPATH=str(copy), RIGFEM_CACHE=str(cache), PYTHONDONTWRITEBYTECODE="1", MPLBACKEND="Agg",
               NUMBA_CACHE_DIR=str(copy.parent / "numba-cache"))
    cmd = ["nice", "-n", "10", sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider",
           "-m", "heavy or not heavy", f"--junitxml={junit}", *tests]
    t0 = time.time()
    try:
        rc = subprocess.run(cmd, cwd=copy, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            timeout=timeout_s).returncode
    except subprocess.TimeoutExpired:
        return -1, [], time.time() - t0
    failed = []
    if junit.exists():
        for case in ET.parse(junit).getroot().iter("testcase"):
            if case.find("failure") is not None or case.find("error") is not None:
                failed.append(f"{case.get('classname')}::{case.get('name')}")
    return rc, failed, time.time() - t0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", nargs="+", metavar="NAME", help="these mutations only")
    ap.add_argument("--list", action="store_true", help="list the mutations and their tests, then exit")
    ap.add_argument("--no-record", action="store_true", help="do not write results/mutation/physics_mutations.*")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds a mutation's tests may take")
    ap.add_argument("--tests", nargs="+", metavar="NODEID",
                    help="run these tests against each mutation instead of its own (implies --no-record)")
    a = ap.parse_args(argv)
    muts = [m for m in MUTATIONS if not a.only or m.name in a.only]
    if a.only and len(muts) != len(a.only):
        ap.error(f"unknown mutation(s): {sorted(set(a.only) - {m.name for m in MUTATIONS})}")
    if a.tests:
        muts, a.no_record = [replace(m, tests=tuple(a.tests)) for m in muts], True
    if a.list:
        for m in muts:
            print(f"{m.name}: {m.file}: {m.what}\n    tests: {', '.join(m.tests)}")
        return 0
    bad = check_snippets(muts)
    if bad:
        print("physics_mutations: a mutation no longer applies:\n  " + "\n  ".join(bad), file=sys.stderr)
        return 2
    started = time.time()
    results = []
    with tempfile.TemporaryDirectory(prefix="rigfem-physmut-") as tmp:
        tmp = Path(tmp)
        copy = tmp / "tree"
        scratch_copy(copy)
        # the unmutated run: every named test passes, and its meshes seed each mutation's cache
        base_cache = tmp / "cache-base"
        tests = list(dict.fromkeys(t for m in muts for t in m.tests))
        rc, failed, secs = run_tests(copy, tests, base_cache, tmp / "base.xml", a.timeout * 2)
        print(f"unmutated: {len(tests)} tests, exit {rc}, {secs:.0f} s", flush=True)
        if rc != 0:
            print(f"physics_mutations: the tests fail without a mutation ({failed or 'exit ' + str(rc)}): fix them first",
                  file=sys.stderr)
            return 2
        for m in muts:
            path = copy / m.file
            original = path.read_text()
            path.write_text(original.replace(m.snippet, m.replacement, 1))
            cache = tmp / f"cache-{m.name}"
            if (base_cache / "meshes").is_dir():
                shutil.copytree(base_cache / "meshes", cache / "meshes")
            try:
                rc, failed, secs = run_tests(copy, m.tests, cache, tmp / f"{m.name}.xml", a.timeout)
            finally:
                path.write_text(original)
                shutil.rmtree(cache, ignore_errors=True)
            status = "killed" if rc in (1, 2) else "timeout" if rc == -1 else "survived" if rc == 0 else f"error (exit {rc})"
            results.append({**asdict(m), "tests": list(m.tests), "status": status, "killed_by": failed[:1],
                            "seconds": round(secs, 1)})
            print(f"{m.name}: {status}{' by ' + failed[0] if failed else ''} ({secs:.0f} s)", flush=True)
    survived = [r["name"] for r in results if r["status"] != "killed"]
    if not a.no_record:
        write_record(results, time.time() - started)
    print(f"{len(results) - len(survived)} of {len(results)} mutations killed"
          + (f"; not killed: {', '.join(survived)}" if survived else ""))
    return 1 if survived else 0


def write_record(results: list[dict], seconds: float) -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    rec = {"name": "physics_mutations",
           "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
           "commit": record.commit(), "machine": record.machine(), "load": os.getloadavg(),
           "command": record.command_line(), "seconds": round(seconds, 1),
           "killed": sum(r["status"] == "killed" for r in results), "mutations": results}
    (OUT / "physics_mutations.json").write_text(json.dumps(rec, indent=1, ensure_ascii=False) + "\n")
    lines = ["# Physics mutations", "",
             f"Command: `{rec['command']}` at {rec['commit']['sha'][:10]}{' (dirty)' if rec['commit']['dirty'] else ''}, "
             f"{rec['date'][:10]}, {rec['seconds'] / 60:.1f} min on {rec['machine']['cores']} shared cores: "
             f"**{rec['killed']} of {len(results)} killed**.  Each bug is planted alone in a scratch copy "
             "(tools/physics_mutations.py) and the tests named run there; the first that failed is listed.", "",
             "| mutation | file | the bug | status | first failing test | s |", "|---|---|---|---|---|---:|"]
    for r in results:
        by = r["killed_by"][0] if r["killed_by"] else "-"
        lines.append(f"| `{r['name']}` | {r['file']} | {r['what']} | {r['status']} | `{by}` | {r['seconds']:.0f} |")
    (OUT / "physics_mutations.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    sys.exit(main())
