"""The documentation's generated pages, and the MkDocs hook that adds them to the site.

    python docs/gen.py OUT_DIR     # write the generated pages into OUT_DIR (to read them without a build)

mkdocs.yml names this file under ``hooks:``, so ``mkdocs build`` calls :func:`on_config` and
:func:`on_files`; nothing it makes is committed, so none of it can fall behind the code:

- ``reference/cli.md``: every ``rigfem`` subcommand, from the argument parsers themselves
  (:func:`rigfem.cli.build_parser`): usage, every option with its help and default, the exit codes;
- ``reference/scene.md``: every table and key of a scene file, from the pydantic JSON schema
  (:meth:`rigfem.schema.SceneFile.model_json_schema`): type, allowed values or range, default,
  required, with a sentence per key from :data:`SCENE_NOTES` (a key without one fails the test
  and the build);
- ``reference/moved.md``: the names moved in 0.2 that still import, with a warning
  (``rigfem.studies.MODULES``/``NAMES``);
- ``examples/*.md``: the gallery, one page per ``examples/*.py`` from its docstring (title,
  description, the output it prints: ``tests/test_examples.py`` runs each script and compares) and
  its source;
- the files under ``results/`` (pictures, reports, animations; not the Markdown tables) copied into
  the site at build time, so a page links ``../results/final-cm/crank_rail.png`` without a second
  copy in git.
"""

from __future__ import annotations

import argparse
import ast
import html
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # the source tree's rigfem, as the tests import it
    sys.path.insert(0, str(ROOT))

EXAMPLES = ROOT / "examples"
RESULTS = ROOT / "results"
#: gallery order (an example not listed comes after these, by name)
GALLERY_ORDER = ["check_custom_scene", "custom_part", "solve_part", "textbook_kinematics", "small_sweep"]


def _cell(text: str) -> str:
    """Plain text for a Markdown table cell: HTML escaped, pipes and newlines made harmless."""
    return html.escape(" ".join(str(text).split()), quote=False).replace("|", "&#124;").replace("*", "&#42;")


def _rst(text: str) -> str:
    """A docstring's ``literal`` as a Markdown `literal`."""
    return re.sub(r"``(.+?)``", r"`\1`", text)


# ----------------------------------------------------------------------------------- CLI reference
def subparsers() -> dict[str, argparse.ArgumentParser]:
    """Every subcommand's full parser, by name (each built as ``rigfem NAME --help`` builds it)."""
    from rigfem.cli import COMMANDS, build_parser

    out = {}
    for name in COMMANDS:
        parser = build_parser([name])
        action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        out[name] = action.choices[name]
    return out


def _option_rows(parser: argparse.ArgumentParser) -> list[str]:
    rows = ["| argument | value | what it does | default |", "|---|---|---|---|"]
    for a in parser._actions:
        if isinstance(a, (argparse._HelpAction, argparse._SubParsersAction)) or a.help == argparse.SUPPRESS:
            continue
        name = ", ".join(a.option_strings) if a.option_strings else a.dest
        takes = a.nargs != 0 and not isinstance(a, (argparse._StoreTrueAction, argparse._StoreFalseAction,
                                                     argparse._StoreConstAction, argparse._CountAction))
        value = ""
        if takes:
            value = " &#124; ".join(map(str, a.choices)) if a.choices else (a.metavar or a.dest.upper())
            value = value if a.choices else _cell(value)
            if a.nargs in ("+", "*") or isinstance(a.nargs, int) and a.nargs > 1:
                value += f" (nargs {a.nargs})"
        default = "" if a.default in (None, False, argparse.SUPPRESS) or not takes and a.default is True else a.default
        rows.append(f"| `{name}` | {value} | {_cell(a.help or '')} | {_cell(default)} |")
    return rows


def cli_reference() -> str:
    """reference/cli.md: the top-level command and every subcommand, from their parsers."""
    import os

    from rigfem.cli import build_parser

    os.environ["COLUMNS"] = "100"  # argparse's usage wraps at the terminal's width: the same page anywhere
    top = build_parser([])
    subs = subparsers()
    lines = ["# Command line reference", "",
             "Generated from rigfem's argument parsers (`rigfem.cli.build_parser`) when the site is built: "
             "what `rigfem COMMAND --help` prints, as tables.  What the exit codes mean in full is on "
             "[Errors and exit codes](../guide/errors.md); the guide's pages show each command at work.", "",
             "```text", top.format_usage().strip(), "```", "", _cell(top.description), "",
             *_option_rows(top), "", "| command | what it does |", "|---|---|",
             *(f"| [`{n}`](#rigfem-{n}) | {_cell(p.description or '')} |" for n, p in subs.items()), ""]
    for name, p in subs.items():
        lines += [f"## rigfem {name}", "", _cell(p.description or ""), "", "```text", p.format_usage().strip(),
                  "```", "", *_option_rows(p), "", _cell(p.epilog or ""), ""]
    return "\n".join(lines)


# ------------------------------------------------------------------------------ scene reference
#: one sentence per key of a scene file (``TABLE.key``); the schema gives type, range and default
SCENE_NOTES: dict[str, str] = {
    "description": "free text shown at the top of every report",
    "linkage": "the linkage: its `type` picks which keys it takes (below)",
    "check": "what a check does; a missing key takes the default of the preset or `rigfem.settings`",
    "linkage.type": "the kind of linkage",
    "linkage.title": "a title for the linkage (reports)",
    "linkage.notes": "free text kept with the linkage",
    "linkage.masses": "`rig`: every bar's mass from the rig catalogue (rails, plates, carriages); `none`: "
                      "the masses of `[linkage.bodies]` (a textbook linkage)",
    "linkage.bodies": "mass data per body, with `masses = \"none\"`",
    "linkage.instant_deg": "a crank angle at which the output holds the given speed and acceleration "
                           "(with `omega_rad_s`, `alpha_rad_s2`)",
    "linkage.alpha_rad_s2": "crank angular acceleration (rad/s²) at `instant_deg`",
    "linkage.textbook": "a textbook linkage (geometry/MECHANISMS.md), not a rig configuration: no rig rule applies",
    "linkage.speed_hz": "crank speed (turns per second; default 1 Hz); give one of `speed_hz`, `rpm`, `omega_rad_s`",
    "linkage.rpm": "crank speed (turns per minute)",
    "linkage.omega_rad_s": "crank angular velocity (rad/s; negative turns clockwise)",
    "linkage.rails_mm": "guide-rail length of each bar (crank, coupler, rocker; mm): its mass and its FE model",
    "linkage.b2": "crank length (mm)",
    "linkage.b3": "coupler (connecting rod) length (mm)",
    "linkage.b4": "rocker length (mm)",
    "linkage.d": "ground length: fixed pivots O2–O4 (mm)",
    "linkage.branch": "assembly branch of the four-bar",
    "linkage.coupler_point": "a point on the coupler whose path is traced",
    "linkage.offset": "slider-crank offset of the slider's line from the crank pivot (mm)",
    "linkage.gas": "a compressor's gas force on the slider",
    "linkage.arm": "inverted slider-crank: length of the arm the block slides on (mm)",
    "linkage.pivot_below": "quick-return: distance of the slotted link's pivot below the crank pivot (mm)",
    "linkage.ram_height": "quick-return: height of the ram's line above the crank pivot (mm)",
    "linkage.coupler_point.distance_mm": "distance of the point from the coupler's first pin (mm)",
    "linkage.coupler_point.angle_deg": "angle of the point from the coupler line (deg)",
    "linkage.gas.p_N": "peak gas force (N)",
    "linkage.gas.L_mm": "cylinder length of the gas-force law (mm)",
    "linkage.gas.c_mm": "clearance of the gas-force law (mm)",
    "linkage.bodies.<name>.mass_kg": "mass of the body (kg)",
    "linkage.bodies.<name>.com_local_mm": "centre of mass in the body's frame (mm)",
    "linkage.bodies.<name>.inertia_com_kg_mm2": "moment of inertia about the centre of mass (kg·mm²)",
    "linkage.bodies.<name>.point_masses": "extra point masses: (name, kg, (x, y) mm in the body's frame)",
    "check.modes": "`original` (the 2013 study's load case) and/or `cycle` (every crank angle, free rails); "
                   "default both",
    "check.parts": "the parts to check (`rigfem parts` lists them); default every part of the linkage type",
    "check.fidelity": "mesh preset (default `standard`): element order, sizes and bearing directions",
    "check.order": "element order: 1 (linear) or 2 (quadratic, curved; the presets' order)",
    "check.size_mm": "global mesh size (mm): meshes exactly that (no adaptive ladder)",
    "check.local_size_mm": "mesh size at loaded interfaces (mm)",
    "check.adaptive": "refine each part only until its verdict is decided (default true)",
    "check.material": "a built-in material (`rig_steel` default, `abs`, `al_6082_t6`) or a table of your own",
    "check.load_factor": "the study's factor on peak reactions in original mode (default 1.4)",
    "check.limit_factor": "criterion: peak < `limit_factor` · σu (default 0.5)",
    "check.bearing_directions": "fixed directions a turning bearing load is split over (default: the preset's)",
    "check.fatigue": "the Goodman fatigue check's Marin factors",
    "check.samples": "crank angles per turn (default 360; peaks are refined between samples)",
    "check.mass_model": "`rigid-body` (default: every bar a rigid body with its true inertia) or `original` "
                        "(the 2013 program, reproduced exactly)",
    "check.frames": "VTU frames of the ParaView animation over the cycle (default 12; 0 none)",
    "check.reactions_csv": "take the reactions from a CSV (as `rigfem reactions --csv` writes) instead of "
                           "rigfem's dynamics",
    "check.reactions_csv_missing": "the value of a column the reactions CSV lacks, stated explicitly",
    "check.reactions_csv_missing.torque_Nm": "the driver torque to assume (N·m)",
    "check.fatigue.surface": "surface finish (Marin surface factor)",
    "check.fatigue.reliability": "reliability (Marin reliability factor)",
    "check.fatigue.size_mm": "effective diameter for the Marin size factor (mm)",
    "check.material.name": "the material's name in reports",
    "check.material.E": "Young's modulus (MPa)",
    "check.material.nu": "Poisson's ratio",
    "check.material.sigma_u": "ultimate tensile strength (MPa)",
    "check.material.density": "density (t/mm³: steel is 7.85e-9)",
}


def _num(x) -> str:
    return f"{x:g}" if isinstance(x, float) else str(x)


def _resolve(schema: dict, defs: dict) -> dict:
    return defs[schema["$ref"].rsplit("/", 1)[1]] if "$ref" in schema else schema


def _kind(s: dict, defs: dict, path: str) -> str:
    """What a value of schema ``s`` may be, in words."""
    if "oneOf" in s:
        return f"table [`[{path}]`](#{_anchor(path)}), by `type`"
    if "anyOf" in s:
        kinds = [_kind(x, defs, path) for x in s["anyOf"] if x.get("type") != "null"]
        return " or ".join(kinds)
    if "$ref" in s:
        return f"table [`[{path}]`](#{_anchor(path)})"
    if "const" in s:
        return f'`"{s["const"]}"`'
    if "enum" in s:
        return " &#124; ".join(f'`{v}`' if not isinstance(v, str) else f'`"{v}"`' for v in s["enum"])
    t = s.get("type")
    rng = ""
    lo = s.get("minimum", s.get("exclusiveMinimum"))
    hi = s.get("maximum", s.get("exclusiveMaximum"))
    if lo is not None or hi is not None:
        lo_s = "" if lo is None else _num(lo) + (" <" if "exclusiveMinimum" in s else " ≤")
        hi_s = "" if hi is None else ("< " if "exclusiveMaximum" in s else "≤ ") + _num(hi)
        rng = f" ({lo_s} x {hi_s})".replace("  ", " ")
    if t == "string":
        n = [f"{s['minLength']}" if "minLength" in s else "", f"{s['maxLength']}" if "maxLength" in s else ""]
        return "text" + (f" (up to {n[1]} characters)" if n[1] else "")
    if t in ("number", "integer"):
        return ("number" if t == "number" else "integer") + rng
    if t == "boolean":
        return "`true` &#124; `false`"
    if t == "array":
        size = (f"{s['minItems']}" if s.get("minItems") == s.get("maxItems") and "minItems" in s else
                "–".join(str(s[k]) for k in ("minItems", "maxItems") if k in s) or "any number of")
        if "prefixItems" in s:
            return f"list ({', '.join(_kind(x, defs, path) for x in s['prefixItems'])})"
        return f"list of {size} × {_kind(s.get('items', {}), defs, path)}"
    if t == "object" and isinstance(s.get("additionalProperties"), dict):
        return f"tables by name, each [`[{path}.<name>]`](#{_anchor(path + '.<name>')})"
    return t or "value"


def _anchor(path: str) -> str:
    return "table-" + re.sub(r"[^a-z0-9]+", "-", path.lower()).strip("-")


def _default(s: dict) -> str:
    if "default" not in s:
        return "**required**"
    d = s["default"]
    if d is None:
        return "see the note"
    if isinstance(d, dict):
        return "each key's own"
    return "`" + (str(d).lower() if isinstance(d, bool) else f'"{d}"' if isinstance(d, str) else _num(d)
                  if not isinstance(d, list) else str(d)) + "`"


def _subtables(s: dict, defs: dict) -> list[tuple[str, dict]]:
    """(suffix, def) of the tables a key's value may be."""
    out = []
    for x in s.get("anyOf", [s]):
        if "$ref" in x:
            out.append(("", _resolve(x, defs)))
        elif x.get("type") == "object" and isinstance(x.get("additionalProperties"), dict) \
                and "$ref" in x["additionalProperties"]:
            out.append((".<name>", _resolve(x["additionalProperties"], defs)))
    return out


def _table(path: str, d: dict, defs: dict, keys: list[str], notes: dict, missing: list[str]) -> list[str]:
    rows = ["| key | value | default | what it is |", "|---|---|---|---|"]
    for k in keys:
        s = d["properties"][k]
        key = f"{path}.{k}" if path else k
        note = notes.get(key.replace(".<name>", ".<name>"))
        if note is None:
            missing.append(key)
            note = ""
        rows.append(f"| `{k}` | {_kind(s, defs, key)} | {_default(s)} | {note} |")
    return rows


def scene_reference(notes: dict[str, str] | None = None) -> tuple[str, list[str]]:
    """(reference/scene.md, the keys of the schema that have no note in ``notes``)."""
    from rigfem.schema import SceneFile

    notes = SCENE_NOTES if notes is None else notes
    schema = SceneFile.model_json_schema()
    defs = schema["$defs"]
    missing: list[str] = []
    lines = ["# Scene file reference", "",
             "Generated from the scene schema (`rigfem/schema.py`, pydantic: "
             "`rigfem.schema.SceneFile.model_json_schema()`) when the site is built.  Units: mm, N, "
             "degrees, Hz, kg; a value outside its range, an unknown table or key (with a did-you-mean), a value "
             "of the wrong type (`order = true`) and NaN or infinity are refused (exit 2, one line naming the "
             "key).  A key whose default reads *see the note* takes it from the fidelity preset or "
             "`rigfem.settings`: the check resolves it.  The [guide](../guide/model.md) shows a whole scene.", "",
             "## The file", "", *_table("", schema, defs, list(schema["properties"]), notes, missing), ""]
    link = schema["properties"]["linkage"]
    kinds = [defs[x["$ref"].rsplit("/", 1)[1]] for x in link["oneOf"]]
    common = [k for k in kinds[0]["properties"] if all(k in d["properties"] for d in kinds) and k != "type"]
    lines += [f'<a id="{_anchor("linkage")}"></a>', "", "## [linkage]", "",
              "`type` is one of " + ", ".join(f'`"{d["properties"]["type"]["const"]}"`' for d in kinds)
              + "; each takes the keys of every linkage and its own.", "", "### Keys of every linkage", "",
              *_table("linkage", kinds[0], defs, common, notes, missing), ""]
    queue: list[tuple[str, dict]] = []
    for d in kinds:
        own = [k for k in d["properties"] if k not in common]
        lines += [f'### type = "{d["properties"]["type"]["const"]}"', "", _rst(d.get("description", "")), "",
                  *_table("linkage", d, defs, own, notes, missing), ""]
        queue += [(f"linkage.{k}{suf}", sub) for k in d["properties"] for suf, sub in _subtables(d["properties"][k], defs)]
    check = _resolve(schema["properties"]["check"], defs)
    queue.insert(0, ("check", check))
    queue += [(f"check.{k}{suf}", sub) for k in check["properties"] for suf, sub in _subtables(check["properties"][k], defs)]
    seen = set()
    for path, d in queue:
        if path in seen:
            continue
        seen.add(path)
        lines += [f'<a id="{_anchor(path)}"></a>', "", f"## [{html.escape(path)}]", "",  # <name>: text, not a tag _rst(d.get("description", "")), "",
                  *_table(path, d, defs, list(d["properties"]), notes, missing), ""]
    return "\n".join(lines), missing


# ---------------------------------------------------------------------------------- moved names
def moved_names() -> str:
    """reference/moved.md: every name a script written before 0.2 may import, and its home now."""
    import rigfem.studies as old

    lines = ["# Moved names", "",
             "Generated from the deprecated alias `rigfem.studies` (`MODULES`, `NAMES`).  A script written "
             "against these names still runs: the import works and warns (`DeprecationWarning`) naming the "
             "new home.  The aliases go in 0.3.", "", "```python",
             "import warnings", "", "with warnings.catch_warnings(record=True) as caught:",
             "    warnings.simplefilter(\"always\")", "    from rigfem.studies import SweepParams  # the old name",
             "from rigfem.sweep import SweepParams as New", "",
             "assert SweepParams is New",
             "print(caught[0].category.__name__, caught[0].message)", "```", "", "```text",
             "DeprecationWarning rigfem.studies.SweepParams moved to rigfem.sweep.configs.SweepParams; "
             "the old name goes in rigfem 0.3",
             "```", "", "## Modules", "", "| old module | new module |", "|---|---|",
             *(f"| `rigfem.studies.{a}` | `rigfem.{b}` |" for a, b in sorted(old.MODULES.items())), "",
             "## Names", "", "| `from rigfem.studies import …` | now in |", "|---|---|",
             *(f"| `{a}` | `rigfem.{b}` |" for a, b in sorted(old.NAMES.items(), key=lambda x: x[0].lower())), ""]
    return "\n".join(lines)


# ------------------------------------------------------------------------------------- gallery
def example(path: Path) -> dict:
    """An example's gallery data from its docstring: title (first line), description, the command
    that runs it (``Run: …``), the output it prints (the indented block after ``Prints``), and the
    source without the docstring."""
    src = path.read_text()
    tree = ast.parse(src)
    doc = ast.get_docstring(tree) or ""
    body = src.split('"""', 2)[2].lstrip("\n") if src.lstrip().startswith('"""') else src
    title, _, rest = doc.partition("\n")
    text, _, prints = rest.partition("\nPrints")
    run = re.search(r"^Run: (.+)$", text, re.M)
    text = re.sub(r"^Run: .+$", "", text, flags=re.M).strip()
    out = prints.partition("\n")[2] if prints else ""
    out_lines = [ln[4:] if ln.startswith("    ") else ln.strip() for ln in out.splitlines()]
    return {"name": path.stem, "file": path.name, "title": title.strip().rstrip("."), "text": _rst(text),
            "run": run.group(1).strip() if run else f"python examples/{path.name}",
            "output": "\n".join(out_lines).strip("\n"), "source": body}


def examples() -> list[dict]:
    found = {p.stem: p for p in EXAMPLES.glob("*.py")}
    order = [n for n in GALLERY_ORDER if n in found] + sorted(set(found) - set(GALLERY_ORDER))
    return [example(found[n]) for n in order]


def gallery() -> dict[str, str]:
    """examples/index.md and one page per example."""
    exs = examples()
    pages = {"examples/index.md": "\n".join(
        ["# Examples", "",
         "Each example is a script in `examples/` that you run from the repository "
         "(`python examples/NAME.py`); `tests/test_examples.py` runs every one and compares what it prints "
         "with the output shown on its page, so the gallery cannot drift from the code.", "",
         "| example | what it shows |", "|---|---|",
         *(f"| [{e['title']}]({e['name']}.md) | `examples/{e['file']}` |" for e in exs), ""])}
    for e in exs:
        extra = [f"The part file it reads, `examples/{p.name}`:\n\n```text\n{p.read_text().strip()}\n```\n"
                 for p in sorted(EXAMPLES.glob("*")) if p.suffix not in (".py",) and p.stem in e["source"]]
        pages[f"examples/{e['name']}.md"] = "\n".join(
            [f"# {e['title']}", "", e["text"], "", "```bash", e["run"], "```", "",
             "prints (checked by `tests/test_examples.py`):", "", "```text", e["output"], "```", "",
             f"`examples/{e['file']}`:", "", "```python", e["source"].rstrip(), "```", "", *extra])
    return pages


def pages(strict: bool = True) -> dict[str, str]:
    """Every generated page: path under docs/ -> Markdown (``strict``: a scene key without a note is an error,
    as the build has it; the tests read the pages without it and name the key in their own test)."""
    scene, missing = scene_reference()
    if missing and strict:
        raise RuntimeError("docs/gen.py: the scene schema has keys without a note in SCENE_NOTES: "
                           + ", ".join(missing))
    return {"reference/cli.md": cli_reference(), "reference/scene.md": scene, "reference/moved.md": moved_names(),
            **gallery()}


def result_files() -> list[Path]:
    """The files under results/ copied into the site: everything but the Markdown and JSON records
    (pages quote those through benchmarks/publish.py) and the VTU/PVD field files (not kept)."""
    return sorted(p for p in RESULTS.rglob("*") if p.is_file() and p.suffix not in (".md", ".json", ".vtu", ".pvd")
                  and not any(part.startswith(".") for part in p.relative_to(ROOT).parts))


# ------------------------------------------------------------------------------------ MkDocs hooks
def on_config(config):
    """The gallery's pages go into the nav under Examples, after its index."""
    names = [{e["title"].split(":")[0]: f"examples/{e['name']}.md"} for e in examples()]
    for i, entry in enumerate(config.nav):
        if isinstance(entry, dict) and "Examples" in entry and isinstance(entry["Examples"], str):
            config.nav[i] = {"Examples": [{"Gallery": entry["Examples"]}, *names]}
    return config


def on_files(files, config):
    from mkdocs.structure.files import File

    for uri, text in pages().items():
        files.append(File.generated(config, uri, content=text))
    for p in result_files():
        files.append(File(str(p.relative_to(ROOT)), src_dir=str(ROOT), dest_dir=config.site_dir,
                          use_directory_urls=config.use_directory_urls))
    return files


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path, help="folder to write the generated pages into")
    a = ap.parse_args(argv)
    for uri, text in pages().items():
        (a.out / uri).parent.mkdir(parents=True, exist_ok=True)
        (a.out / uri).write_text(text)
        print(f"wrote {a.out / uri}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
