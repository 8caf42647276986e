"""How non-conservative is the rectangular rail profile?  The 700 mm crank rail of final-cm under
the 2013 study's load case, solved for profile variants of geometry/rail_size25.toml.

Run: ``python benchmarks/rail_profile_study.py [--fidelity draft|standard]``
-> results/rail_profile/study.md and study.json.

The load case is the check pipeline's own (``rigfem check final-cm``, crank_rail, original
mode: load factor × peak far-joint reaction split over the last two holes, rail held by the
screws of its pivot coupling); only the part's dimensions change (``PartCase.params``).
Section properties come from the gross 2-D section (no screw holes) built with gmsh OCC;
linear masses are for the 1000 mm rail with its 17 holes, as in ``rigfem parts``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time
from pathlib import Path

import gmsh

from rigfem.cache import from_environment
from rigfem.context import Context
from rigfem.fe import Plan, solve_cases
from rigfem.job import Request, read_job
from rigfem.mesh import gmsh_session, mass_kg
from rigfem.pipeline import load_cases
from rigfem.rig import load_part
from rigfem.verdict import judge

OUT = Path(__file__).resolve().parents[1] / "results" / "rail_profile"
SCENE = "final-cm"
#: variant -> (dimension overrides of rail_size25, what it stands for)
VARIANTS: dict[str, tuple[dict[str, float], str]] = {
    "rectangle": ({"groove_radius": 0.0}, "full 23 x 24 rectangle (the default until 2026-11-21)"),
    "grooves r2.5": ({"groove_radius": 2.5, "groove_z_lower": 8.0, "groove_z_upper": 18.0},
                     "four simplified raceway grooves r = 2.5 mm at z = 8 and 18"),
    "grooves r4.6 (catalogue mass)": (
        {"groove_radius": 4.6, "groove_z_lower": 7.0, "groove_z_upper": 18.0},
        "the default profile: grooves r = 4.6 mm at z = 7 and 18, sized so the 1000 mm rail weighs "
        "the catalogue's 3.1 kg/m (upper groove leaves a 1.4 mm wall to the counterbore)"),
    "waist 11.95 (catalogue mass)": (
        {"groove_radius": 0.0, "waist_width": 11.95},
        "assumed: the rail narrowed to 11.95 mm between z = 2 and 14 (below the counterbore "
        "floor), sized for the catalogue's 3.1 kg/m with the material taken lower down"),
}


def section(part) -> dict[str, float]:
    """Gross section (y-z plane, no holes) of a rail: area mm^2, centroid z, I_y, I_z mm^4.

    I_y = ∫(z - z_c)^2 dA (vertical bending), I_z = ∫y^2 dA (bending in the linkage plane).
    """
    W, H, rg, ww = part["width"], part["height"], part["groove_radius"], part["waist_width"]
    with gmsh_session("section"):
        occ = gmsh.model.occ
        face = [(2, occ.addRectangle(-W / 2, 0, 0, W, H))]  # local (y, z) drawn as gmsh (x, y)
        tools = []
        if rg > 0:
            tools += [(2, occ.addDisk(y, z, 0, rg, rg)) for y in (-W / 2, W / 2)
                      for z in (part["groove_z_lower"], part["groove_z_upper"])]
        if ww > 0:
            za, zb = part["waist_z_lower"], part["waist_z_upper"]
            tools += [(2, occ.addRectangle(y0, za, 0, (W - ww) / 2 + 1, zb - za))
                      for y0 in (-W / 2 - 1, ww / 2)]
        if tools:
            face, _ = occ.cut(face, tools)
        occ.synchronize()
        (d, t), = face
        area = occ.getMass(d, t)
        yc, zc, _ = occ.getCenterOfMass(d, t)
        m = occ.getMatrixOfInertia(d, t)  # about the centroid; gmsh (x, y) = local (y, z)
    return {"area_mm2": area, "zc_mm": zc, "yc_mm": yc, "I_y_mm4": m[0], "I_z_mm4": m[4]}


def section_hand(part) -> tuple[float, float]:
    """Area and I_z by hand: rectangle minus four half-disc grooves or minus the waist strips.

    A half disc (area πr²/2) has the first moment 2r³/3 about its flat side and πr⁴/8 as second
    moment, so each groove removes (W/2)²·πr²/2 − W·2r³/3 + πr⁴/8 from I_z = H·W³/12; a waist
    of width w over a height h_w removes (W − w)·h_w of area and h_w·(W³ − w³)/12 of I_z.
    """
    W, H, rg, ww = part["width"], part["height"], part["groove_radius"], part["waist_width"]
    hw = part["waist_z_upper"] - part["waist_z_lower"] if ww > 0 else 0.0
    area = W * H - 4 * math.pi * rg**2 / 2 - (W - ww) * hw
    iz = (H * W**3 / 12 - hw * (W**3 - ww**3) / 12
          - 4 * ((W / 2) ** 2 * math.pi * rg**2 / 2 - W * 2 * rg**3 / 3 + math.pi * rg**4 / 8))
    return area, iz


def study(fidelity: str) -> tuple[list[dict], list[str], object]:
    """Every variant of the crank rail's original-mode case at one fidelity preset."""
    ctx = Context(from_environment())
    job = read_job(Request(SCENE, {"parts": ["crank_rail"], "modes": ["original"], "fidelity": fidelity}), ctx.cache)
    _, ((mode, base),) = load_cases(job, ctx)
    rows = []
    for name, (dims, what) in VARIANTS.items():
        rail = load_part("rail_size25", dims)  # 1000 mm: linear mass as in `rigfem parts`
        sec = section(rail)
        a_hand, iz_hand = section_hand(rail)
        assert math.isclose(sec["area_mm2"], a_hand, rel_tol=1e-6), (name, sec, a_hand)
        assert math.isclose(sec["I_z_mm4"], iz_hand, rel_tol=1e-6), (name, sec, iz_hand)
        case = dataclasses.replace(base, params={**base.params, **dims})
        t = time.perf_counter()
        res, = solve_cases([(mode, case)], job.settings, Plan(frames=None), ctx)
        rows.append({"variant": name, "what": what, "dims": dims, **sec,
                     "kg_per_m": mass_kg(rail) / rail["length"] * 1000,
                     "peak_mpa": res.peak.value, "surface": res.peak.surface,
                     "xyz": [round(c, 2) for c in res.peak.xyz], "zz_error": res.peak.zz_error,
                     "utilisation_pct": judge([res.outcome], job.settings).parts[0].verdict.utilisation_pct,
                     "nodes": len(res.mesh.points), "seconds": time.perf_counter() - t})
        print(f"{fidelity} {name}: {rows[-1]['kg_per_m']:.3f} kg/m, peak {res.peak.value:.1f} MPa at "
              f"{res.peak.surface} {rows[-1]['xyz']}, {rows[-1]['seconds']:.1f} s", flush=True)
    for r in rows:
        r["peak_ratio"] = r["peak_mpa"] / rows[0]["peak_mpa"]
        r["bending_ratio_z"] = rows[0]["I_z_mm4"] / r["I_z_mm4"]  # same outer fibre y = W/2
    return rows, base.notes, job.settings


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fidelity", nargs="+", default=["draft", "standard"],
                    choices=("draft", "standard", "fine"))
    args = ap.parse_args()
    runs = {f: study(f) for f in args.fidelity}
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "study.json").write_text(json.dumps(
        {"scene": SCENE, "case": next(iter(runs.values()))[1], "rows": {f: r[0] for f, r in runs.items()}},
        indent=1))
    write_md(runs, args.fidelity)
    print(f"wrote {OUT / 'study.md'}")


def write_md(runs: dict, fidelities: list[str]) -> None:
    """results/rail_profile/study.md: one table per fidelity, the case and the command."""
    rows0, notes, _ = next(iter(runs.values()))
    lines = [
        "# Rail profile study: how much the unknown rail profile matters",
        "",
        f"Command: `python benchmarks/rail_profile_study.py --fidelity {' '.join(fidelities)}`",
        "",
        f"Case: {SCENE}, crank_rail (700 mm), original mode (the check pipeline's own case) — "
        f"{'; '.join(notes)}.  Only the rail's dimensions change.",
        "Section: gross section without screw holes (gmsh OCC, checked against a hand formula); "
        "linear mass: 1000 mm rail with its 17 holes (catalogue 3.1 kg/m, 2013 study 2.7 kg/m).",
        "I_y = ∫(z−z_c)² dA (vertical bending), I_z = ∫y² dA (bending in the linkage plane, "
        "what the study's in-plane load does).  σ_b ratio = I_z(rectangle)/I_z: nominal in-plane "
        "bending stress at the outer fibre y = ±11.5 mm relative to the rectangle.",
        "",
        "| variant | area mm² | kg/m | I_y mm⁴ | I_z mm⁴ | σ_b ratio |",
        "|---|---|---|---|---|---|",
    ]
    lines += [f"| {r['variant']} | {r['area_mm2']:.1f} | {r['kg_per_m']:.3f} | {r['I_y_mm4']:.0f} | "
              f"{r['I_z_mm4']:.0f} | {r['bending_ratio_z']:.3f} |" for r in rows0]
    for fid, (rows, _, s) in runs.items():
        lines += ["", f"## FE peak von Mises, fidelity {fid} (order {s.order}, size {s.size_mm:g} mm, "
                  f"local {s.local_size_mm:g} mm)", "",
                  "| variant | peak MPa | peak / rectangle | σ_b ratio | peak at (surface, x y z mm) "
                  "| ZZ error | utilisation % | nodes |", "|---|---|---|---|---|---|---|---|"]
        lines += [f"| {r['variant']} | {r['peak_mpa']:.1f} | {r['peak_ratio']:.3f} | "
                  f"{r['bending_ratio_z']:.3f} | {r['surface']} {r['xyz']} | {r['zz_error']:.2f} | "
                  f"{r['utilisation_pct']:.1f} | {r['nodes']} |" for r in rows]
    last = runs[fidelities[-1]][0]
    cat = [r["peak_ratio"] for r in last if "catalogue" in r["variant"]]
    lines += ["", f"Reading ({fidelities[-1]}): a profile with the catalogue's 3.1 kg/m raises the rail's "
              f"peak by a factor {min(cat):.2f}–{max(cat):.2f} over the rectangle, close to its I_z ratio "
              "(the peak is in-plane bending at the outer fibre beside the pivot coupling's outer "
              "screw hole_02, not a hole-bearing peak), so it depends on where the real profile lacks "
              "material, which is unknown; a profile as light as the study's 2.7 kg/m would raise it "
              "further.  This is why the default profile is the weaker catalogue-mass variant, the "
              "grooves r4.6 (geometry/rail_size25.toml); the rectangle, the default before, "
              f"under-estimated the rail's peak by up to ×{max(cat):.1f}."]
    lines += ["", "Variants:", *[f"- **{r['variant']}**: {r['what']}; overrides {r['dims'] or 'none'}"
                                 for r in rows0], ""]
    (OUT / "study.md").write_text("\n".join(lines))


if __name__ == "__main__":
    main()
