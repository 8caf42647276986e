"""``rigfem mesh``: mesh one part with gmsh and write it as .vtu or .msh."""

from __future__ import annotations

import argparse
from dataclasses import replace
from typing import TYPE_CHECKING

from rigfem import rig  # lazy (lazy_loader)
from rigfem.cli.outputs import new_output, write_file
from rigfem.errors import InputError, check_range, plain
from rigfem.settings import FIDELITY, MeshSettings, preset

if TYPE_CHECKING:
    from rigfem.mesh.partmesh import PartMesh

HELP = "mesh a part (known name or .geo/.step/.brep file) and write .vtu or .msh"
#: allowed element sizes (mm): global, and the smallest local size; beyond them the cost estimate
#: or the floats themselves fail (1e-300 divides by zero, 1e300 overflows)
SIZE_MM = (0.01, 10_000.0)
LOCAL_MIN_MM = 0.001
#: allowed magnitude of a dimension (--length, --set), mm
DIM_MM = 1e6
#: the meaning of exit code 0 (the command has no verdict)
SUCCESS = "mesh written"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from rigfem.mesh.mesher import DEFAULT_SIZE  # the mesh code loads for `rigfem mesh` only, not for --help

    parser.add_argument("part", metavar="PART", help="part name (see `rigfem parts`) or geometry file")
    parser.add_argument("--length", type=float, metavar="MM", help="part length, mm (rails: any length)")
    parser.add_argument("--fidelity", choices=list(FIDELITY), metavar="PRESET",
                        help=f"start from a check's mesh preset ({' | '.join(FIDELITY)}); --size and "
                             f"--local-size override it")
    parser.add_argument("--size", type=float, metavar="MM",
                        help="global element size, mm (default: the preset's, else by kind: "
                             + ", ".join(f"{k} {v:g}" for k, v in DEFAULT_SIZE.items()) + ")")
    parser.add_argument("--refine", default="", metavar="G1,G2",
                        help="surface groups that carry load, refined (e.g. hole_10,hole_11)")
    parser.add_argument("--local-size", "--refine-size", dest="local_size", type=float, metavar="MM",
                        help="size at the refined groups, mm (default: the preset's, else size/4)")
    parser.add_argument("--order", type=int, choices=(1, 2), default=1, help="1: tetra, 2: tetra10 (default 1)")
    parser.add_argument("--set", action="append", default=[], metavar="DIM=VALUE",
                        help="override a dimension of the part file, mm (repeatable)")
    parser.add_argument("--min-quality", type=float, default=0.1, help="smallest allowed minSICN (default 0.1)")
    parser.add_argument("--no-cache", action="store_true", help="remesh even if a cached mesh exists")
    parser.add_argument("--out", required=True, metavar="FILE", help="output .vtu or .msh")
    parser.add_argument("--force", action="store_true", help="replace an existing --out file (only one rigfem wrote)")


def _overrides(args: argparse.Namespace) -> dict[str, float]:
    out: dict[str, float] = {}
    for item in args.set:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise InputError(f"--set {item!r} must look like DIM=VALUE, e.g. thickness=12")
        out[key.strip()] = check_range(f"--set {plain(key.strip(), 40)}", value, -DIM_MM, DIM_MM, "mm")
    if args.length is not None:
        out["length"] = check_range("--length", args.length, 0.0, DIM_MM, "mm", lo_open=True)
    return out


def _settings(args: argparse.Namespace, kind: str) -> MeshSettings:
    """The preset (or the kind's default size), with the options given on top of it."""
    from rigfem.mesh.mesher import DEFAULT_SIZE

    base = preset(args.fidelity) if args.fidelity else MeshSettings(DEFAULT_SIZE[kind])
    size = check_range("--size", args.size if args.size is not None else base.size_mm, *SIZE_MM, "mm")
    local = args.local_size if args.local_size is not None else (base.local_size_mm if args.fidelity else None)
    if local is not None:
        check_range("--local-size", local, LOCAL_MIN_MM, size, "mm")
    refine = tuple(g.strip() for g in args.refine.split(",") if g.strip())
    return replace(base, size_mm=size, local_size_mm=local, refine=refine,
                   min_quality=check_range("--min-quality", args.min_quality, 0.0, 1.0))


def refinement(pm: PartMesh, settings: MeshSettings) -> str:
    """Where the mesh is finer than the global size, by surface name: the groups refined on
    request and the curved ones that curvature sizing meshes finer, or why nothing is."""
    said = []
    if settings.refine:
        said.append(f"refined on {', '.join(settings.refine)} to {settings.near_mm:g} mm")
    curved = pm.meta.get("curved", {})
    if curved:
        said.append("finer by curvature on " + ", ".join(f"{k} ({v:.2g} mm)" for k, v in sorted(curved.items())))
    if not said:
        return (f"no surface refined: every surface at the global size (name load-carrying groups with "
                f"--refine; groups: {', '.join(sorted(pm.surfaces))})")
    return "; ".join(said)


def run(args: argparse.Namespace) -> int:
    from rigfem.mesh.mesher import mesh_part
    from rigfem.mesh.partmesh import write_mesh

    out = new_output("--out", args.out, (".vtu", ".msh"), args.force)
    for flag, value, lo in (("--size", args.size, SIZE_MM[0]), ("--local-size", args.local_size, LOCAL_MIN_MM)):
        if value is not None:  # at the edge: before the part is read
            check_range(flag, value, lo, SIZE_MM[1], "mm")
    part = rig.load_part(args.part, _overrides(args))
    settings = _settings(args, part.kind)
    from rigfem.cache import NO_CACHE, from_environment

    pm = mesh_part(part, settings, cache=NO_CACHE if args.no_cache else from_environment())
    write_file(out, lambda tmp: write_mesh(pm, tmp, args.order))
    q, m = pm.quality, pm.meta
    dims = ", ".join(f"{k} {d.value:g}" for k, d in part.dims.items() if d.source == "override")
    print(f"{part.name}{f' ({dims} mm)' if dims else ''}: {len(pm.points)} nodes, {len(pm.tets)} tets, "
          f"global size {settings.size_mm:g} mm{f' ({args.fidelity} preset)' if args.fidelity else ''}")
    print(refinement(pm, settings))
    print(f"quality minSICN: min {q['min']:.3f}, p01 {q['p01']:.3f}, p05 {q['p05']:.3f}, median {q['median']:.3f}")
    how = "cache hit (meshed earlier in" if m["cache"] == "hit" else "meshed (cache miss) in"
    print(f"estimate {m['estimate_tets']} tets, {m['estimate_gib']:.3g} GiB; {how} {m['seconds']:.2f} s"
          f"{')' if m['cache'] == 'hit' else ''}")
    print(f"curved boundary: {len(pm.curved_edges)} edges whose P2 node lies on the geometry")
    print(f"groups: {', '.join(sorted(pm.surfaces))}")
    print(f"wrote {args.out} (order {args.order})")
    return 0
