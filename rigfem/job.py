"""What a check is asked (:class:`Request`), what it is made of once read (:class:`Job`) and what it found (:class:`Checked`).

:func:`read_job` is the scene stage, the edge where a request is validated: the scene file and
its ``[check]`` table against :mod:`rigfem.schema`, the linkage built with the forces it names,
the parts resolved against their definitions, the rig rules, the material and the reactions CSV
(read here, once).
Everything after it trusts the Job.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from collections.abc import Mapping
from pathlib import Path

from rigfem.cache import Cache
from rigfem.dynamics.forces import loaded_linkage
from rigfem.dynamics.history import DynamicsOptions, ReactionHistory, Reactions
from rigfem.errors import InputError, plain
from rigfem.fe.partcase import CaseResult
from rigfem.io.reactions_csv import read_csv
from rigfem.linkage.mechanisms import crank_angles
from rigfem.linkage.model import Linkage
from rigfem.material import table_material
from rigfem.rig.rules import broken_rules, rules_for
from rigfem.scene import Scene, load_scene, resolve
from rigfem.schema import validate_check
from rigfem.settings import REFERENCE_SCENE, CheckSettings, check_mass_model, part_settings
from rigfem.verdict.part import Verdicts

__all__ = ["Request", "Job", "Checked", "read_job"]

#: [check] fields about the dynamics and outputs (the rest is rigfem.settings)
_DYNAMICS = {"samples": 360, "mass_model": "rigid-body", "frames": 12, "reactions_csv": None,
             "reactions_csv_missing": None}


@dataclasses.dataclass(frozen=True)
class Request:
    """A check as asked: a scene (file or built-in name), ``[check]`` fields that override the
    scene's (``{"fidelity": "draft", "parts": ["plate_A"]}``), whether a configuration that
    breaks a rig rule is checked anyway, and who signs the report."""

    scene: str | Path = REFERENCE_SCENE
    overrides: Mapping = dataclasses.field(default_factory=dict)
    allow_rule_violations: bool = False
    author: str | None = None  #: the report's author (None: the scene's ``[report] author``)


@dataclasses.dataclass(frozen=True)
class Job:
    """A scene read for checking: its linkage with the forces it names, the check's settings, how
    the reactions are got, the animation frames, the rig rules it breaks (allowed explicitly) and
    whether they apply (not to a textbook linkage), the hashes of its inputs, the report's author and
    its reactions CSV as read."""

    scene: Scene
    linkage: Linkage
    settings: CheckSettings
    dynamics: DynamicsOptions
    frames: int  #: VTU frames of the cycle animation (0: none)
    rule_violations: tuple[str, ...] = ()
    description: str = ""
    scene_sha256: str = ""  #: SHA-256 of the scene file's bytes
    input_sha256: str = ""  #: SHA-256 of everything the result depends on (scene, [check] as run, reactions CSV)
    author: str = ""
    rig_rules: bool = True  #: whether the rig rules apply (a rig configuration, not a textbook linkage)
    #: the reactions CSV (``dynamics.reactions_csv``) as read, checked against the linkage's joints; None without one
    external: ReactionHistory | None = None

    @property
    def crank_deg(self):
        """The crank angles of the turn (deg, ``dynamics.samples`` of them)."""
        return crank_angles(self.dynamics.samples)


@dataclasses.dataclass(frozen=True)
class Checked:
    """Everything a check found: the job, its reactions, every part case solved and the verdicts."""

    job: Job
    reactions: Reactions
    results: tuple[CaseResult, ...]
    verdicts: Verdicts


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def read_job(request: Request, cache: Cache) -> Job:
    """The scene stage: read and validate ``request`` into a :class:`Job` (InputError, one line,
    for anything wrong with it; ``cache`` remembers scenes validated before).

    A rig scene that breaks a rig rule is refused (naming the rule and its numbers) unless the
    request allows it; then the violations are kept for the verdict and the report."""
    path = resolve(request.scene)
    sc = load_scene(path, cache)
    table = {**sc.raw.get("check", {}), **request.overrides}
    validate_check(table, path.name)
    dyn = {k: table.pop(k, v) for k, v in _DYNAMICS.items()}
    lk = loaded_linkage(sc)
    if not lk.loads and not any(b.totals()[0] > 0 for b in lk.bodies):  # no mass, no external force
        raise InputError(f"scene {plain(sc.name, 80)!r}: nothing loads its parts (no masses, no external "
                         f"force), so a stress check would pass at 0 %; for its motion alone use rigfem kinematics")
    settings = part_settings(table, lk.meta["type"], lk.meta.get("rails_mm"))
    csv_path = None
    if dyn["reactions_csv"] is not None:
        csv_path = path.parent / str(dyn["reactions_csv"])
        if not csv_path.is_file():
            raise InputError(f"[check].reactions_csv = {plain(str(dyn['reactions_csv']), 80)!r}: no such file "
                             f"next to the scene ({plain(str(csv_path), 120)})")
    options = DynamicsOptions(int(dyn["samples"]), dyn["mass_model"], sc.speed_hz, csv_path,
                              dyn["reactions_csv_missing"])
    if csv_path is None:  # (an imported CSV's reactions use no mass model)
        check_mass_model(options.mass_model, lk.meta)
        external = None
    else:
        external = read_csv(csv_path, options.csv_missing, tuple(j.name for j in lk.joints))
    settings = dataclasses.replace(settings, material=table_material(table.get("material", "rig_steel")))
    # a rig scene is built from the rig's catalogue; the textbook linkages (masses = "none") have no rig rules.
    # The rules come last, so that --allow-rule-violations never uncovers another input error.
    rig_rules = sc.raw.get("linkage", {}).get("masses", "rig") == "rig" and bool(rules_for(lk.meta))
    broken = broken_rules(lk.meta) if rig_rules else []
    if broken and not request.allow_rule_violations:
        raise InputError(f"scene {plain(path.name, 80)!r} breaks the rig rule {broken[0]}"
                         f"{f' (and {len(broken) - 1} more)' if len(broken) > 1 else ''}: it does not meet "
                         f"the rig rules; pass --allow-rule-violations to check it anyway")
    scene_sha = _sha256(path.read_bytes())
    inputs = {"scene": scene_sha, "allow_rule_violations": bool(broken),  # the CSV by its content, not its path
              "check": {**table, **dyn, "reactions_csv": _sha256(csv_path.read_bytes()) if csv_path else None}}
    author = request.author if request.author is not None else sc.raw.get("report", {}).get("author", "")
    return Job(sc, lk, settings, options, int(dyn["frames"]), tuple(broken),
               sc.raw.get("description", sc.raw["linkage"].get("title", "")), scene_sha,
               _sha256(json.dumps(inputs, sort_keys=True, separators=(",", ":"), default=str).encode()),
               plain(author, 200), rig_rules, external)
