"""What a report states of its part cases, in one place: labels, the error band three ways, why a
mesh stopped, factors of safety, the governing case.  Plain functions of the report's entries
(:mod:`rigfem.report.document` renders them; the pictures, the HTML and the terminal print them)."""

from __future__ import annotations

import math

#: the pictures of a part case (rigfem.report.pictures.part_pictures): utilisation (von Mises), displacement,
#: factor of safety
PICTURES = ("von_mises", "displacement", "safety_factor")


def part_label(name: str, part: str) -> str:
    """The one name a reader sees for a part: its role and its catalogue name, ``crank_rail (rail_size25)``."""
    return f"{name} ({part})"


def allowable_label(limit_factor: float, limit_mpa: float) -> str:
    """The allowable stress written one way everywhere: ``allowable σu/2 = 375 MPa``."""
    sym = "σu/2" if limit_factor == 0.5 else f"{limit_factor:g}·σu"
    return f"allowable {sym} = {limit_mpa:.0f} MPa"


def safety_factor(peak_mpa: float | None, against_mpa: float) -> float | None:
    """``against / peak`` (–), None when there is no stress to divide by."""
    return None if not peak_mpa else against_mpa / peak_mpa


def conclusion(parts: list[dict], limit_mpa: float, sigma_u_mpa: float) -> dict | None:
    """The governing part case (highest utilisation), its utilisation with the band, the minimum
    factor of safety (against the allowable and against σu) and the reserve to the limit at the
    band's top; None when no stress was computed."""
    solved = [p for p in parts if p.get("peak_mpa") is not None]
    if not solved:
        return None
    g = max(solved, key=lambda p: p["utilisation_pct"])
    half = g["utilisation_pct"] * g["error_pct"] / 100
    return {"name": g["name"], "part": g["part"], "mode": g["mode"], "verdict": g["verdict"],
            "peak_mpa": g["peak_mpa"], "crank_deg": g.get("crank_deg"), "utilisation_pct": g["utilisation_pct"],
            "utilisation_band_pct": [g["utilisation_pct"] - half, g["utilisation_pct"] + half],
            "band_mpa": g["peak_mpa"] * g["error_pct"] / 100, "error_pct": g["error_pct"],
            "min_safety_factor": safety_factor(g["peak_mpa"], limit_mpa),
            "min_safety_factor_ultimate": safety_factor(g["peak_mpa"], sigma_u_mpa),
            "reserve_pct": 100.0 - (g["utilisation_pct"] + half),
            "reserve_mpa": limit_mpa - g["peak_mpa"] * (1 + g["error_pct"] / 100)}


def band(p: dict) -> dict | None:
    """The error band of a part case's peak three ways: ± MPa, ± % of the allowable, ± % of the peak
    (None without a peak).  A schema-4 report, which has only ``error_pct``, gives the same numbers."""
    if p.get("peak_mpa") is None:
        return None
    e = p["error_pct"]
    return {"mpa": p.get("band_mpa", p["peak_mpa"] * e / 100),
            "pct_of_allowable": p.get("band_pct_of_allowable", p["utilisation_pct"] * e / 100), "pct_of_peak": e}


def band_text(p: dict) -> str:
    """The band as printed: ``±3.5 MPa = ±0.9 % of the allowable (±43.7 % of the peak)``."""
    b = band(p)
    if b is None:
        return "–"
    return f"±{b['mpa']:.1f} MPa = ±{b['pct_of_allowable']:.1f} % of the allowable (±{b['pct_of_peak']:.1f} % of the peak)"


def stopped_text(p: dict) -> str:
    """Why the part's mesh stopped refining (the adaptive ladder), ``–`` when not recorded."""
    m = p.get("mesh") or {}
    return m.get("stopped") or "–"


def asked_text(p: dict) -> str:
    """What the check asked of the part's mesh (``mesh.asked``): ``fine: band ≤ ±1 % of the allowable
    and ≤ ±5 % of the peak, coarse up to fine``; ``–`` when not recorded (a report before schema 6)."""
    a = (p.get("mesh") or {}).get("asked")
    if not a:
        return "–"
    if not a["adaptive"]:
        return f"{a['fidelity']}: one fixed mesh ({a['cap']}), no target"
    peak = f" and ≤ ±{a['target_pct_of_peak']:g} % of the peak" if a.get("target_pct_of_peak") is not None else ""
    return f"{a['fidelity']}: band ≤ ±{a['target_pct_of_allowable']:g} % of the allowable{peak}, coarse up to {a['cap']}"


def by_utilisation(parts: list[dict]) -> list[dict]:
    """The part cases, highest utilisation first (unsolved ones, which fail, at the top)."""
    return sorted(parts, key=lambda p: -math.inf if p.get("peak_mpa") is None else -p["utilisation_pct"])


def part_minima(parts: list[dict]) -> list[dict]:
    """Per part, its minimum factor of safety over the modes checked and the mode that gives it."""
    out: dict[str, dict] = {}
    for p in parts:
        sf = p.get("safety_factor")
        if sf is None:
            continue
        if p["name"] not in out or sf < out[p["name"]]["min_safety_factor"]:
            out[p["name"]] = {"name": p["name"], "part": p["part"], "mode": p["mode"], "min_safety_factor": sf,
                              "min_safety_factor_ultimate": p["safety_factor_ultimate"]}
    return sorted(out.values(), key=lambda m: m["min_safety_factor"])


def number(x: float | None, nd: int = 1) -> str:
    """A number as a report prints it: ``nd`` decimals, ``–`` when there is none, and 0.0 where it
    rounds to zero (never -0.0, which reads as a sign that means something).

    >>> number(-1e-9), number(-0.06), number(None)
    ('0.0', '-0.1', '–')
    """
    return "–" if x is None else f"{round(x, nd) + 0.0:.{nd}f}"


def sf_text(x) -> str:
    """A factor of safety as printed: two decimals, ``–`` when there is none."""
    return "–" if x is None else f"{x:.2f}"
