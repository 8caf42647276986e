"""``rigfem parts``: list the known parts with their key dimensions and masses."""

from __future__ import annotations

import argparse

from rigfem import rig  # lazy (lazy_loader)

HELP = "list the known parts (geometry/*.toml) with dimensions and masses"
#: the meaning of exit code 0 (the command has no verdict)
SUCCESS = "part list printed"

_KEY_DIMS = {"rail": ("length", "width", "height", "pitch"),
             "plate": ("diameter", "thickness", "bore_diameter", "screw_spacing"),
             "iprofile": ("length", "flange_width", "height")}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--sources", action="store_true", help="also print every dimension with its source")


def run(args: argparse.Namespace) -> int:
    from rigfem.cache import from_environment
    from rigfem.mesh.volume import mass_kg  # cached OpenCASCADE volumes (gmsh only on a cache miss)

    cache = from_environment()

    print(f"parts in {rig.GEOMETRY_DIR} (mm, kg):")
    for name, (path, _) in rig.known_parts().items():
        part = rig.load_part(name)
        m = mass_kg(part, cache)
        dims = ", ".join(f"{k} {part[k]:g}" for k in _KEY_DIMS.get(part.kind, ()))
        note = ""
        if part.kind == "rail":
            per_m = m / part["length"] * 1000
            ref = part.reference
            note = (f"; {rig.rail_hole_count(part)} holes; {per_m:.3f} kg/m "
                    f"(catalogue {ref['linear_mass_catalogue'].value:g}: "
                    f"{100 * (per_m / ref['linear_mass_catalogue'].value - 1):+.1f} %, "
                    f"study {ref['linear_mass_study'].value:g}: "
                    f"{100 * (per_m / ref['linear_mass_study'].value - 1):+.1f} %)")
        elif "mass" in part.reference:
            note = f" (study {part.reference['mass'].value:g}: {100 * (m / part.reference['mass'].value - 1):+.1f} %)"
        print(f"  {name:14s} {part.kind:8s} {path.name:22s} {dims}; mass {m:.3f}{note}")
        if args.sources:
            for k, d in part.dims.items():
                print(f"      {k:16s} {d.value:>8g} {d.unit:3s} {d.source}")
    print("custom parts: pass a .geo (physical groups) or .step/.stp/.brep (named entities) file as PART")
    return 0
