"""Mutation testing of rigfem's numerical core with mutmut 3, and the dated record of its scores.

    python tools/mutation_testing.py verdict loads dynamics fe        # run, then write the record
    python tools/mutation_testing.py --report                         # the record again from the last runs
    python tools/mutation_testing.py fe-stress --retest               # its record's survivors again, against new tests
    python tools/mutation_testing.py fe-loads --sample 150            # a random sample of its mutants, scored with a 95 % interval

Each package is mutated in a scratch copy of this work tree (``--workdir``, default
``/tmp/rigfem-mutmut/<package>``): the copy's pyproject.toml gets the package's ``[tool.mutmut]``
table (:data:`PACKAGES`: what to mutate, and the fast tests against independent truths that may kill
a mutant; mutmut runs, for each mutant, only those of them that reach the mutated function).  The
run has no rigfem cache (``RIGFEM_CACHE`` under /proc, which rigfem refuses and then runs
without one): mutmut's copy holds every mutant at once, selected at run time, so every mutant has
the same source hash and a cached mesh or solution would hide it.

The record (``results/mutation/mutmut.json`` and ``.md``) holds, per package, the date, commit,
dirty flag, machine, command, mutmut's counts and score, and every mutant that was not killed with
its diff and its fate: ``text`` (only the text of a message changes: a string literal, or a string
argument that only names a value in an error message, replaced), ``equivalent`` (with the argument
why, from ``tools/mutation_fates.toml``) or ``open``.  The physics score leaves the ``text``
mutants out, and those argued equivalent or of code no number depends on: (killed + timeout + crash)
/ the rest.

A package whose mutants take longer than a session (fe/: about half a minute each on two cores)
is scored on a uniform random sample (``--sample N``, ``--seed``): its names drawn from every
mutant mutmut makes of the package (mutmut's own generator), run as a whole run would run them;
the record says "N of M" and gives each score with its 95 % Wilson interval.
"""

from __future__ import annotations

import argparse
import datetime
import importlib
import io
import glob
import json
import math
import os
import platform
import random
import re
import shutil
import subprocess
import sys
import time
import tokenize
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "results" / "mutation"
FATES = ROOT / "tools" / "mutation_fates.toml"
sys.path.insert(0, str(ROOT / "benchmarks"))
record = importlib.import_module("record")  # benchmarks/record.py, a sibling script: machine(), commit()

sys.path.insert(0, str(ROOT / "tools"))
from physics_mutations import scratch_copy  # noqa: E402

FE_TESTS = ["tests/test_fe_closed_form.py", "tests/test_fe_cantilever.py", "tests/test_fe_patch.py",
            "tests/test_fe_loads.py", "tests/test_fe_freebody.py", "tests/test_fe_components.py",
            "tests/test_fe_assembly.py::test_stiffness_equals_skfem_generic",
            "tests/test_fe_assembly.py::test_curved_stiffness_equals_skfem_isoparametric",
            "tests/test_band_coverage.py::test_band_covers_the_bending_stress_of_a_beam",
            "tests/test_band_coverage.py::test_band_covers_the_lame_bore_stress",
            "tests/test_band_coverage.py::test_peak_error_pct_is_the_calibrated_zz_estimate_in_percent",
            "tests/test_physics_truths.py", "tests/test_fe_truths.py", "tests/test_report_entry_truths.py",
            "tests/test_fe_loads_truths.py",
            "tests/test_reference_scenes.py::test_final_cm_parts_reproduce_their_committed_figures[plates]"]
#: a mutant's pytest forks from a server that has only collected the tests: forked from the main
#: process, which has run them, it hangs in MKL/OpenMP or gmsh's threads (every fe/ mutant, and half
#: of a mesh-sizing sample, timed out); the other packages fork from the main process, ten times faster
FORKSERVER = {"process_isolation": "forkserver"}
#: package -> what mutmut mutates (globs), the tests it may run (fast, against independent truths),
#: the environment of its runs (``env``) and any other key of mutmut's table
PACKAGES = {
    "verdict": {"mutate": ["rigfem/verdict/*"],
                "tests": ["tests/test_verdict.py", "tests/test_trust.py::test_criterion_never_passes_unloaded_or_unbalanced",
                          "tests/test_verdict_truths.py", "tests/test_report_entry_truths.py",
                          "tests/test_reference_scenes.py::test_final_cm_parts_reproduce_their_committed_figures[plates]"]},
    "loads": {"mutate": ["rigfem/loads/*"],
              "tests": ["tests/test_loadcases.py", "tests/test_physics_truths.py", "tests/test_load_cases_truths.py"]},
    "dynamics": {"mutate": ["rigfem/dynamics/*"],
                 "tests": ["tests/test_dynamics_closed.py", "tests/test_original.py", "tests/test_reactions.py",
                           "tests/test_mechanisms.py", "tests/test_loadcases.py", "tests/test_partial_turn.py",
                           "tests/test_physics_truths.py", "tests/test_load_cases_truths.py", "tests/test_dynamics_truths.py",
                           "tests/test_dynamics_solver_truths.py", "tests/test_dynamics_history_truths.py",
                           "tests/test_original_truths.py", "tests/test_linkage.py",
                           # the command line at a change point warns nothing (numpy's errstate)
                           "tests/test_change_points.py::test_the_2013_model_sampled_at_a_change_point_reports_a_toggle"],
                 # peaks' bracket search loops until the bracket is narrow (history._zoom_max): a mutant
                 # that stops it shrinking loops for ever, and mutmut's CPU budget, 2 × multiplier × (the
                 # tests' time + constant), at its defaults (15, 1 s) let each run minutes; 3 and 5 s give
                 # a mutant at least 30 s (a forked pytest's start costs seconds: a budget of 5 s timed
                 # out mutants that the tests kill or that survive) and six times its tests' time
                 "timeout_multiplier": 3.0, "timeout_constant": 5.0},
    # the kinematics (closed forms, loop closure, change points), the mechanism catalogue and synthesis
    "linkage": {"mutate": ["rigfem/linkage/*"],
                "tests": ["tests/test_kinematics.py", "tests/test_linkage.py", "tests/test_linkage_state.py",
                          "tests/test_synthesis.py", "tests/test_mechanisms.py", "tests/test_extremes_linkage.py",
                          "tests/test_dynamics_closed.py", "tests/test_dynamics_truths.py", "tests/test_change_points.py",
                          "tests/test_cli_kinematics.py", "tests/test_bad_input_campaign.py", "tests/test_rig_design.py",
                          "tests/test_original_truths.py", "tests/test_dynamics_solver_truths.py",
                          "tests/test_linkage_truths.py", "tests/test_mechanisms_truths.py",
                          "tests/test_synthesis_truths.py", "tests/test_linkage_expression_truths.py"]},
    # mesh sizing: the size fields, the tet and memory estimates, second order and the quality gate
    # (gmsh in this process, RIGFEM_MESH_IN_PROCESS: mutmut's coverage sees no child process)
    "mesh-sizing": {"mutate": ["rigfem/mesh/mesher.py"], "tests": ["tests/test_mesh.py", "tests/test_mesh_sizing_truths.py"],
                    "env": {"RIGFEM_MESH_IN_PROCESS": "1"}, **FORKSERVER},
    # fe/'s numerical modules, in three runs (about 3000 mutants: hours on two shared cores)
    "fe-stress": {"mutate": ["rigfem/fe/stress.py", "rigfem/tensors.py", "rigfem/fe/solution.py"], "tests": FE_TESTS,
                  **FORKSERVER},
    # and the stiffness's null space, the rigid modes of supports.py (free bodies are held by them)
    "fe-loads": {"mutate": [f"rigfem/fe/{m}.py" for m in ("forces", "supports")],
                 "tests": FE_TESTS + ["tests/test_fe_assembly.py::test_stiffness_symmetric_and_rigid_modes_in_kernel"],
                 **FORKSERVER},
    # and every test of the assembly: its warm-up (compile_kernels) and the straightening of distorted
    # curved elements are reached by no other
    "fe-assembly": {"mutate": ["rigfem/fe/assembly.py"],
                    "tests": [t for t in FE_TESTS if not t.startswith("tests/test_fe_assembly.py")]
                    + ["tests/test_fe_assembly.py"], **FORKSERVER},
}
#: the mutmut of this Python (its venv need not be on PATH)
MUTMUT = shutil.which("mutmut", path=str(Path(sys.executable).parent)) or "mutmut"
NO_CACHE = "/proc/rigfem-mutmut-no-cache"  # rigfem refuses a cache folder under /proc and runs without one


def mutmut_table(pkg: str) -> str:
    """The ``[tool.mutmut]`` table of a package's run (pyproject.toml's own, with the package's paths and tests)."""
    base = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["mutmut"]
    cfg = {**base, "only_mutate": PACKAGES[pkg]["mutate"],
           "pytest_add_cli_args_test_selection": PACKAGES[pkg]["tests"],
           **{k: v for k, v in PACKAGES[pkg].items() if k not in ("mutate", "tests", "env")}}
    return "[tool.mutmut]\n" + "".join(f"{k} = {json.dumps(v)}\n" for k, v in cfg.items())


def _prepare(pkg: str, d: Path) -> None:
    """A scratch copy of the work tree at ``d`` whose pyproject.toml holds the package's mutmut table."""
    scratch_copy(d)
    text = (d / "pyproject.toml").read_text()
    text = re.sub(r"\n\[tool\.mutmut\]\n(?:(?!\n\[).)*", "\n", text, flags=re.S)  # the package's table instead
    (d / "pyproject.toml").write_text(text.rstrip("\n") + "\n\n" + mutmut_table(pkg))


#: run in a package's scratch folder: the name of every mutant mutmut makes there (its generator,
#: under the package's [tool.mutmut] table)
_NAMES = """
import json
from pathlib import Path
from mutmut.mutation.file_mutation import mutate_file_contents
from mutmut.utils.file_utils import walk_mutatable_files
from mutmut.utils.format_utils import get_mutant_name
print(json.dumps(sorted(get_mutant_name(Path(f), n) for f in walk_mutatable_files()
                        for n in mutate_file_contents(str(f), Path(f).read_text()).mutant_names)))
"""


def _env() -> dict[str, str]:
    """This environment without PYTHONPATH: a run in a scratch copy imports the copy's rigfem."""
    return {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}


def _names(d: Path) -> list[str]:
    """Every mutant of the package prepared in ``d``."""
    return json.loads(subprocess.run([sys.executable, "-c", _NAMES], cwd=d, env=_env(), capture_output=True,
                                     text=True, check=True).stdout)


def draw(d: Path, n: int, seed: int) -> dict:
    """A uniform random sample of ``n`` of the mutants of the package prepared in ``d``: {n, of, seed, names}."""
    every = _names(d)
    if not 0 < n < len(every):
        raise SystemExit(f"--sample {n}: {d.name} has {len(every)} mutants; sample from 1 to {len(every) - 1}, "
                         f"or run them all without --sample")
    return {"n": n, "of": len(every), "seed": seed, "names": sorted(random.Random(seed).sample(every, n))}


def run_package(pkg: str, work: Path, children: int, resume: bool = False,
                sample: tuple[int, int] | None = None) -> dict:
    """Run the package (or a random sample of its mutants: ``sample`` = (n, seed)); the run's time,
    and the sample drawn."""
    d = work / pkg
    resumed = resume and (d / "mutants").is_dir()  # mutmut keeps the results it has: it runs the rest
    if not resumed:
        _prepare(pkg, d)
    drawn = draw(d, *sample) if sample else None
    names = drawn["names"] if drawn else []
    if drawn and resumed:  # mutmut re-runs every mutant named: name only those without a result
        done = {k for k, (status, _) in results(d).items() if status != "not checked"}
        names = [n for n in names if n not in done] or names[:1]
    return {**_mutmut(pkg, d, children, names), **({"sample": drawn} if drawn else {})}


def retest_package(pkg: str, work: Path, children: int) -> tuple[dict, dict, bool]:
    """Run the mutants the package's record did not kill again, in a fresh copy, against this
    tree's tests (new tests written to kill them); (the run's time, the record it started from,
    whether the whole sample ran).
    mutmut names a mutant by its function and number, so the names are the record's only while the
    mutated files are as they were at the record's commit.  Where they changed since, a sampled
    record's whole sample is run again (``retest: {"whole_sample": ...}``: its kills are this tree's too);
    a full run's record is refused (run the package afresh).  ``of`` counts the package's mutants
    at this tree."""

    prev = json.loads((OUT / "mutmut.json").read_text())["packages"].get(pkg) if (OUT / "mutmut.json").exists() else None
    if not prev:
        raise SystemExit(f"--retest {pkg}: {OUT / 'mutmut.json'} has no record of {pkg}; run it first")
    files = sorted(f for pattern in PACKAGES[pkg]["mutate"] for f in glob.glob(pattern, root_dir=ROOT))
    diff = subprocess.run(["git", "-C", str(ROOT), "diff", "--name-only", prev["commit"]["sha"], "--", *files],
                          capture_output=True, text=True)
    changed = bool(prev["commit"]["dirty"] or diff.returncode or diff.stdout.strip())
    if changed and not prev.get("sample"):
        raise SystemExit(f"--retest {pkg}: the mutated files are not those of the record "
                         f"({prev['commit']['sha'][:10]}{', dirty' if prev['commit']['dirty'] else ''}): "
                         f"run the package afresh")
    if not changed and not prev["not_killed"]:
        raise SystemExit(f"--retest {pkg}: its record has no mutant left to kill")
    d = work / pkg
    _prepare(pkg, d)
    (d / "seconds.txt").unlink(missing_ok=True)
    if not changed:
        return _mutmut(pkg, d, children, [m["mutant"] for m in prev["not_killed"]]), prev, False
    names, every = prev["sample"]["names"], _names(d)
    gone = sorted(set(names) - set(every))
    if gone:
        raise SystemExit(f"--retest {pkg}: {len(gone)} of its sample ({gone[:3]}) are no mutants of the changed "
                         f"files; draw a fresh sample (--sample N --seed S)")
    return {**_mutmut(pkg, d, children, names), "of": len(every)}, prev, True


def _mutmut(pkg: str, d: Path, children: int, names: list[str] = ()) -> dict:
    env = _env()
    env.update(RIGFEM_CACHE=NO_CACHE, RIGFEM_TESTS_KEEP_CACHE="1",  # tests/conftest.py would point it at a folder
               NUMBA_CACHE_DIR=str(d / ".numba-cache"), MPLBACKEND="Agg",
               **dict.fromkeys(("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS"), "1"),
               **PACKAGES[pkg].get("env", {}))  # the package's own
    t0 = time.time()
    with open(d / "mutmut.log", "a") as log:
        rc = subprocess.run(["nice", "-n", "10", MUTMUT, "run", "--max-children", str(children), *names],
                            cwd=d, env=env, stdout=log, stderr=subprocess.STDOUT).returncode
    spent = d / "seconds.txt"  # an interrupted run's time counts too
    seconds = time.time() - t0 + (float(spent.read_text()) if spent.exists() else 0.0)
    spent.write_text(f"{seconds:.1f}")
    if rc != 0:
        raise SystemExit(f"mutmut run failed in {d} (exit {rc}): see {d / 'mutmut.log'}")
    return {"seconds": round(seconds, 1)}


#: run in a package's scratch folder: every mutant's status and, for those not killed, its diff (one
#: process: ``mutmut show`` per mutant costs a second each)
_READ = """
import json
from mutmut.mutation.data import SourceFileMutationData
from mutmut.mutation.diff_apply import get_diff_for_mutant
from mutmut.stats import status_by_exit_code
from mutmut.utils.file_utils import walk_mutatable_files
out = {}
for path in walk_mutatable_files():
    m = SourceFileMutationData(path=path)
    m.load()
    for name, code in m.exit_code_by_key.items():
        status = status_by_exit_code[code]
        if isinstance(code, int) and code < 0 and status != "timeout":
            # a crash (illegal instruction, abort, bus error, floating-point trap, segfault) fails the test
            # run; mutmut's CPU limit (SIGXCPU) is its timeout; any other signal (a stopped run's SIGTERM,
            # the OOM killer's SIGKILL) decides nothing
            status = "segfault" if -code in (4, 6, 7, 8, 11) else "interrupted"
        # a diff for what the record lists: not for a kill, nor for a mutant a sample did not draw
        out[name] = [status, "" if status in ("killed", "not checked") else get_diff_for_mutant(name, path=path)]
print(json.dumps(out))
"""


def results(d: Path) -> dict[str, tuple[str, str]]:
    """mutant -> (status, diff of the mutant if not killed)."""
    out = subprocess.run([sys.executable, "-c", _READ], cwd=d, env=_env(), capture_output=True, text=True, check=True).stdout
    return {k: (s, "\n".join(ln for ln in p.splitlines() if ln[:1] in "-+" and ln[:3] not in ("---", "+++")))
            for k, (s, p) in json.loads(out).items()}


def _tokens(line: str) -> list[tuple[int, str]]:
    """The tokens of one line of a diff; a continuation line that closes brackets opened on an
    earlier line (a message's second half) is read with those brackets opened first."""
    for opened in ("", "(", "(("):
        try:
            toks = list(tokenize.generate_tokens(io.StringIO(opened + line.strip() + "\n").readline))
        except (tokenize.TokenError, IndentationError, SyntaxError):
            continue
        return [(t.type, t.string) for t in toks[len(opened):]
                if t.type not in (tokenize.NEWLINE, tokenize.NL, tokenize.ENDMARKER, tokenize.INDENT, tokenize.DEDENT)]
    return [(-1, line)]


#: where a string literal is only text a person reads: an exception, a note or reason, a warning, the
#: field name and unit ``check_range`` puts in its message
MESSAGE = re.compile(r"raise |Error\(|notes|reason|warn|print\(|check_range\(|_refuse|InputError|ComputeError")


def category(patch: str) -> str:
    """``text`` when the mutant only changes what a message says: every changed token is a string
    literal (an f-string, or any string on a line that builds a message: :data:`MESSAGE`) replaced by
    another string or by None, or an exception's message replaced by None; else ``code`` (a changed
    dictionary key or compared string is code: something reads it)."""
    old = [ln[1:] for ln in patch.splitlines() if ln.startswith("-")]
    new = [ln[1:] for ln in patch.splitlines() if ln.startswith("+")]
    m = re.fullmatch(r"\s*raise (\w+)\(None\)", new[0]) if len(new) == 1 else None
    if m and old and old[0].strip().startswith(f"raise {m.group(1)}("):
        return "text"
    if len(old) != 1 or len(new) != 1:
        return "code"
    a, b = _tokens(old[0]), _tokens(new[0])
    if len(a) != len(b):
        return "code"
    changed = [(x, y) for x, y in zip(a, b) if x != y]
    strings = all(x[0] == tokenize.STRING and (y[0] == tokenize.STRING or y == (tokenize.NAME, "None")) for x, y in changed)
    message = MESSAGE.search(old[0]) or all(x[1].lower().startswith(("f'", 'f"')) for x, _ in changed)
    return "text" if changed and strings and message else "code"


#: mutants equivalent by construction, recognised from their diff: (the line with this text replaced
#: by that one, why).  Listed with each such mutant in the record.
EQUIVALENT_EDITS = [
    ((", dtype=float)", ", dtype=None)"), "dtype: every value reaching it is a float already (numpy float arrays, "
     "Python floats), so asking for float changes nothing"),
    ((", dtype=float)", ", )"), "dtype: every value reaching it is a float already, so asking for float changes nothing"),
    ((", float)", ", None)"), "dtype: every value reaching it is a float already, so asking for float changes nothing"),
    ((", float)", ", )"), "dtype: every value reaching it is a float already, so asking for float changes nothing"),
]


def equivalent_edit(patch: str) -> str:
    old = [ln[1:] for ln in patch.splitlines() if ln.startswith("-")]
    new = [ln[1:] for ln in patch.splitlines() if ln.startswith("+")]
    if len(old) == 1 and len(new) == 1:
        for (a, b), why in EQUIVALENT_EDITS:
            if a in old[0] and old[0].replace(a, b, 1) == new[0]:
                return why
    return ""


def wilson(k: int, n: int, z: float = 1.96) -> list[float]:
    """The 95 % Wilson score interval (%) of a proportion ``k`` of ``n``."""
    p, zz = k / n, z * z / n
    centre, half = (p + zz / 2) / (1 + zz), z * math.sqrt(p * (1 - p) / n + zz / (4 * n)) / (1 + zz)
    return [round(100 * (centre - half), 1), round(100 * (centre + half), 1)]


def summarise(pkg: str, d: Path, meta: dict, prior: dict | None = None, whole: bool = False) -> dict:
    """The record of a package's run in ``d``; with ``prior`` (the record a ``--retest`` re-ran the
    survivors of), its killed mutants stay killed and the re-run decides the rest, or, ``whole``
    (the files changed since: the sample ran again), the re-run decides every mutant; a sampled
    run (``meta["sample"]``) counts its sample only."""
    fates = tomllib.loads(FATES.read_text()) if FATES.exists() else {}
    res = results(d)
    sample = meta.get("sample")
    counts: dict[str, int] = {}
    if prior is None or whole:  # every mutant run (of the sample, if drawn) decided here
        run = set(sample["names"]) if sample else set(res)
    else:  # the prior record's survivors decided again; its kills stand
        run = {m["mutant"] for m in prior["not_killed"]}
        counts = dict(prior["counts"])
        for m in prior["not_killed"]:
            counts[m["status"]] -= 1
    res = {k: v for k, v in res.items() if k in run}
    unrun = sorted(k for k in run if res.get(k, ("not checked",))[0] == "not checked")
    if unrun and (sample or prior is not None):
        raise SystemExit(f"{'--sample' if prior is None else '--retest'} {pkg}: mutmut did not run {len(unrun)} "
                         f"of the mutants it had to ({unrun[:3]}…)")
    for s, _ in res.values():
        counts[s] = counts.get(s, 0) + 1
    counts = {k: v for k, v in counts.items() if v}
    not_killed = []
    for name, (status, patch) in sorted(res.items()):
        if status in ("killed", "timeout", "segfault"):
            continue
        cat = category(patch)
        why = (fates.get("equivalent", {}).get(name, "") or equivalent_edit(patch)
               or next((w for f, w in fates.get("dead_code", {}).items() if name.startswith(f + "__mutmut_")), ""))
        infra = next((w for f, w in fates.get("not_numerical", {}).items() if name.startswith(f + "__mutmut_")), "")
        fate = "text" if cat == "text" else "equivalent" if why else "not numerical" if infra else "open"
        why = why or infra
        not_killed.append({"mutant": name, "status": status, "diff": patch, "fate": fate, "why": why})
    text = sum(1 for m in not_killed if m["fate"] in ("text", "not numerical"))
    total = sum(counts.values())
    # a mutant whose tests hang (timeout) or crash the interpreter (segfault: any signal that kills the
    # test process, e.g. a kernel writing outside a badly sized array) fails the test run as a killed one does
    killed = counts.get("killed", 0) + counts.get("timeout", 0) + counts.get("segfault", 0)
    equivalent = sum(1 for m in not_killed if m["fate"] == "equivalent")
    physics_total = total - text - equivalent
    # a sample's score estimates the package's, with its interval, until tests are written for its own
    # survivors: re-run (--retest), it says how far those tests got, no longer what the package scores
    interval = ({"ci95_mutmut_pct": wilson(killed, total) if total else None,
                 "ci95_physics_pct": wilson(killed, physics_total) if physics_total else None}
                if sample and prior is None else {})
    return {"package": pkg, "mutate": PACKAGES[pkg]["mutate"], "tests": PACKAGES[pkg]["tests"],
            **({"env": PACKAGES[pkg]["env"]} if PACKAGES[pkg].get("env") else {}), **meta,
            "counts": counts, "total": total,
            "score_mutmut_pct": round(100 * killed / total, 1) if total else None,
            "text_mutants": text, "equivalent": equivalent,
            "open": sum(1 for m in not_killed if m["fate"] == "open"),
            "score_physics_pct": round(100 * killed / physics_total, 1) if physics_total else None,
            **interval, "not_killed": not_killed}


def _now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


def write(record_by_pkg: dict, command: str) -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / "mutmut.json"
    old = json.loads(path.read_text()) if path.exists() else {"packages": {}}
    stamp = {"date": _now(),
             "commit": record.commit(), "machine": record.machine(), "command": command,
             "mutmut": _version("mutmut")}
    for pkg, rec in record_by_pkg.items():
        old["packages"][pkg] = {**stamp, **rec}
    old["name"] = "mutmut"
    path.write_text(json.dumps(old, indent=1, ensure_ascii=False) + "\n")
    (OUT / "mutmut.md").write_text(markdown(old))


def _version(pkg: str) -> str | None:
    from importlib import metadata
    try:
        return metadata.version(pkg)
    except metadata.PackageNotFoundError:
        return None


def _again(p: dict) -> str:
    """What a retested record re-ran of its first run."""
    r = p.get("retest") or {}
    if "whole_sample" not in r:
        return "the survivors"
    w = r["whole_sample"]
    return (f"the whole sample run again at changed files ({w['date'][:10]}, {w['commit']['sha'][:10]})"
            + (", then its survivors," if r.get("survivors_after") else ","))


def markdown(rec: dict) -> str:
    lines = ["# Mutation testing of the numerical core (mutmut)", "",
             "Written by `tools/mutation_testing.py` from its runs (the command of each package below); "
             "the raw record is `mutmut.json`.  *mutmut score* = (killed + timeout + crash) / all: every "
             "mutant that fails the test run (a crash: the test process died of a signal).  "
             "*physics score* = (killed + timeout + crash) / (all − mutants that only change a message's "
             "text − mutants of "
             "code no number depends on (tools/mutation_fates.toml [not_numerical]) − mutants argued "
             "equivalent).  Every mutant not killed but for message text is listed below with its fate: "
             "`equivalent` (with the argument), `not numerical` (why), or `open` (a test could kill it; "
             "none does yet).  A package scored on a random sample of its mutants (`--sample`) shows "
             "*n of N* mutants and each score with its 95 % Wilson interval.", "",
             "| package | mutated | mutants | killed | survived | no tests | timeout | crash | text or not numerical | equivalent | mutmut score | physics score | date, commit | command |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|"]
    def score(p: dict, kind: str) -> str:
        retested = p.get("sample") and p.get("first_run")
        ci = None if retested else p.get(f"ci95_{kind}_pct")
        return f"{p[f'score_{kind}_pct']} %" + (f" ({ci[0]}–{ci[1]} %)" if ci else
                                                " (the sample's, after tests for its survivors)" if retested else "")

    for pkg, p in rec["packages"].items():
        c, smp = p["counts"], p.get("sample")
        now = ((p.get("retest") or {}).get("whole_sample") or {}).get("mutants_now")
        n = (f"{p['total']} of {smp['of']} (random, seed {smp['seed']}{f'; {now} today' if now else ''})"
             if smp else p["total"])
        lines.append(f"| {pkg} | {', '.join(p['mutate'])} | {n} | {c.get('killed', 0)} | {c.get('survived', 0)} | "
                     f"{c.get('no tests', 0)} | {c.get('timeout', 0)} | {c.get('segfault', 0)} | {p['text_mutants']} | {p['equivalent']} | "
                     f"{score(p, 'mutmut')} | **{score(p, 'physics')}** | {p['date'][:10]}, "
                     f"{p['commit']['sha'][:10]}{' (dirty)' if p['commit']['dirty'] else ''} | `{p['command']}`"
                     + (f" ({_again(p)} of `{p['first_run']['command']}`, {p['first_run']['date'][:10]}, "
                        f"{p['first_run']['commit']['sha'][:10]})" if p.get("first_run") else "") + " |")
    for pkg, p in rec["packages"].items():
        open_ = [m for m in p["not_killed"] if m["fate"] != "text"]
        lines += ["", f"## {pkg}: mutants not killed, but for message text ({len(open_)})", "",
                  f"Tests: {', '.join(p['tests'])}"
                  + "".join(f"; environment {k}={v}" for k, v in (p.get("env") or {}).items()), ""]
        for m in open_:
            why = f" — {m['why']}" if m["why"] else ""
            lines += [f"- `{m['mutant']}` ({m['status']}, {m['fate']}){why}", "", "  ```diff",
                      *("  " + ln for ln in m["diff"].splitlines()), "  ```"]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("packages", nargs="*", help=f"of {', '.join(PACKAGES)} (default: all)")
    ap.add_argument("--workdir", type=Path, default=Path("/tmp/rigfem-mutmut"))
    ap.add_argument("--max-children", type=int, default=1)
    ap.add_argument("--report", action="store_true", help="rewrite the record from the last runs in --workdir")
    ap.add_argument("--resume", action="store_true", help="continue an interrupted run in --workdir (its copy as it is)")
    ap.add_argument("--retest", action="store_true",
                    help="run the mutants the package's record did not kill again (a fresh copy), against this tree's tests")
    ap.add_argument("--sample", type=int, metavar="N",
                    help="run a uniform random sample of N of the package's mutants (scores with 95 %% intervals)")
    ap.add_argument("--seed", type=int, default=0, help="the sample's random seed (default 0)")
    ap.add_argument("--markdown", action="store_true", help="rewrite mutmut.md from mutmut.json (nothing is run)")
    a = ap.parse_args(argv)
    if a.markdown:
        (OUT / "mutmut.md").write_text(markdown(json.loads((OUT / "mutmut.json").read_text())))
        return 0
    pkgs = a.packages or list(PACKAGES)
    if set(pkgs) - set(PACKAGES):
        ap.error(f"unknown package(s) {sorted(set(pkgs) - set(PACKAGES))}: choose from {', '.join(PACKAGES)}")
    if a.sample is not None and (a.retest or a.report):
        ap.error("--sample draws a new run: not with --retest or --report (they keep the record's sample)")
    if a.sample is not None and not a.resume and (OUT / "mutmut.json").exists():
        rec = json.loads((OUT / "mutmut.json").read_text())["packages"]
        used = [p for p in pkgs if (rec.get(p, {}).get("sample") or {}).get("seed") == a.seed]
        if used:  # tests written for that sample's survivors would make a second draw of it look better
            ap.error(f"--seed {a.seed}: the record's sample of {', '.join(used)} was drawn with it; "
                     f"draw a fresh one (--seed {a.seed + 1})")
    recs = {}
    for pkg in pkgs:
        meta = {}
        prior, whole = None, False
        if a.retest:
            meta, prior, whole = retest_package(pkg, a.workdir, a.max_children)
            first = prior.get("first_run") or {k: prior[k] for k in ("date", "commit", "command")}
            # once its whole sample ran again at changed files, the record says so from then on: when,
            # at which commit, and how many mutants the files have since (the sample keeps the count it
            # was drawn from); its time starts there (the first run's results were all decided again)
            retest = ({"whole_sample": {"date": _now(), "commit": record.commit(), "mutants_now": meta["of"]}}
                      if whole else {**prior["retest"], "survivors_after": True} if prior.get("retest") else None)
            seconds = meta["seconds"] + (0.0 if whole else prior["seconds"])
            meta = {"seconds": round(seconds, 1), "first_run": first,
                    **({"sample": prior["sample"]} if prior.get("sample") else {}),
                    **({"retest": retest} if retest else {})}
        elif not a.report:
            meta = run_package(pkg, a.workdir, a.max_children, a.resume,
                               None if a.sample is None else (a.sample, a.seed))
        else:
            prev = json.loads((OUT / "mutmut.json").read_text())["packages"].get(pkg, {}) if (OUT / "mutmut.json").exists() else {}
            if prev.get("first_run"):  # its folder holds only the re-run mutants: the others would read as unrun
                raise SystemExit(f"--report {pkg}: its record is a --retest's, whose folder holds only the "
                                 f"mutants it re-ran; run --retest again instead")
            # the run's own stamp (its date, commit and command), and when it was summarised again
            meta = {"seconds": prev.get("seconds"), **({"sample": prev["sample"]} if prev.get("sample") else {}),
                    **{k: prev[k] for k in ("date", "commit", "command", "machine", "mutate", "tests", "mutmut")
                       if k in prev},
                    "summarised": {"date": _now(),
                                   "commit": record.commit(), "command": record.command_line()}}
        recs[pkg] = summarise(pkg, a.workdir / pkg, meta, prior, whole)
        p = recs[pkg]
        print(f"{pkg}: {p['total']} mutants, {p['counts']}, mutmut score {p['score_mutmut_pct']} %, "
              f"physics score {p['score_physics_pct']} %", flush=True)
        write({pkg: p}, record.command_line())  # each package's record as soon as it is done
    return 0


if __name__ == "__main__":
    sys.exit(main())
