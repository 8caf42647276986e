"""Isotropic linear-elastic materials.

Values are in the rig's unit system mm–N–MPa–t (density in t/mm³), but a
:class:`Material` is unit-agnostic: give E in Pa and density in kg/m³ for an
m–N–Pa–kg model.

>>> from rigfem.material import get_material, lame
>>> steel = get_material("rig_steel")
>>> steel.E, steel.nu, steel.sigma_u
(210000.0, 0.3, 750.0)
>>> lame(210000.0, 0.3)
(121153.84615384616, 80769.23076923077)
"""

from __future__ import annotations

from dataclasses import dataclass

from rigfem.errors import InputError, check_range


def lame(E: float, nu: float) -> tuple[float, float]:
    """Lamé parameters (λ, μ) of an isotropic material: the one place they are computed."""
    return E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))


@dataclass(frozen=True)
class Material:
    """Isotropic material: E and ultimate strength in MPa, density in t/mm³."""

    name: str
    E: float  #: Young's modulus
    nu: float  #: Poisson's ratio
    sigma_u: float  #: ultimate tensile strength
    density: float  #: mass density (7.85e-9 t/mm³ for steel)

    def __post_init__(self) -> None:
        check_range(f"material {self.name!r} E", self.E, 0.0, None, lo_open=True)
        check_range(f"material {self.name!r} nu", self.nu, -0.99, 0.49)
        check_range(f"material {self.name!r} sigma_u", self.sigma_u, 0.0, None, lo_open=True)
        check_range(f"material {self.name!r} density", self.density, 0.0, None)

    @property
    def lame(self) -> tuple[float, float]:
        """Lamé parameters (λ, μ)."""
        return lame(self.E, self.nu)


#: the Marin factors of a fatigue check (rigfem.verdict.fatigue), here so that the scene schema
#: names the allowed surfaces and reliabilities without loading any of the verdict or FE code
#: Marin surface factor k_a = a·Sut^b, Sut in MPa (Shigley Table 6-2)
SURFACE = {"ground": (1.58, -0.085), "machined": (4.51, -0.265), "cold-drawn": (4.51, -0.265),
           "hot-rolled": (57.7, -0.718), "as-forged": (272.0, -0.995)}


#: Marin reliability factor k_e (Shigley Table 6-5)
RELIABILITY = {0.5: 1.0, 0.9: 0.897, 0.95: 0.868, 0.99: 0.814, 0.999: 0.753, 0.9999: 0.702}


#: Marin load factor k_c; for combined loading assessed by von Mises, k_c = 1 (Shigley §6-14)
LOADING = {"bending": 1.0, "combined": 1.0, "axial": 0.85, "torsion": 0.59}


MATERIALS: dict[str, Material] = {
    "rig_steel": Material("rig_steel", 210000.0, 0.3, 750.0, 7.85e-9),
    "abs": Material("abs", 2200.0, 0.35, 40.0, 1.04e-9),
    # EN AW-6082-T6 (EN 755-2, t ≤ 5 mm): Rm ≥ 310 MPa, E 70 GPa, ν 0.33, 2700 kg/m³
    "al_6082_t6": Material("al_6082_t6", 70000.0, 0.33, 310.0, 2.70e-9),
}


#: where each library material's values come from (report.json's material table); σy is listed
#: as absent where the source gives none: the criterion (σu/2) does not use it
SOURCES: dict[str, dict[str, str]] = {
    "rig_steel": dict.fromkeys(("E", "nu", "sigma_u", "density"), "2013 study (geometry/RIG.md §5)")
    | {"sigma_y": "not given by the 2013 study; not used by the criterion"},
    "abs": dict.fromkeys(("E", "nu", "sigma_u"), "2013 study (geometry/RIG.md §5)")
    | {"density": "assumed: typical ABS (geometry/RIG.md §5)",
       "sigma_y": "not given by the 2013 study; not used by the criterion"},
    "al_6082_t6": dict.fromkeys(("E", "nu", "sigma_u", "density"), "EN 755-2 (t ≤ 5 mm) and typical values")
    | {"sigma_y": "not recorded in rigfem; not used by the criterion"},
}


def material_sources(m: Material) -> dict[str, str]:
    """Source of each value of ``m``: the library's, or the scene's own [material] table."""
    if MATERIALS.get(m.name) == m:
        return SOURCES[m.name]
    return dict.fromkeys(("E", "nu", "sigma_u", "density", "sigma_y"), "the scene's [check].material table") | {
        "sigma_y": "not given; not used by the criterion"}


def get_material(name: str) -> Material:
    """Material from the library by name."""
    try:
        return MATERIALS[name]
    except KeyError:
        raise InputError(f"material = {name!r} is unknown; allowed: {', '.join(MATERIALS)}") from None


def material_from_dict(d: dict) -> Material:
    """User-defined material of a scene, in mm–N–MPa–t: ``{"name", "E", "nu", "sigma_u", "density"}``.

    The ranges catch values given in SI by mistake (E in Pa, density in kg/m³), which would
    otherwise make every part pass.

    >>> material_from_dict({"name": "s355", "E": 210e3, "nu": 0.3, "sigma_u": 470, "density": 7.85e-9}).E
    210000.0
    """
    keys = ("name", "E", "nu", "sigma_u", "density")
    missing = [k for k in keys if k not in d]
    extra = [k for k in d if k not in keys]
    if missing or extra:
        raise InputError(f"material fields must be exactly {keys}; missing {missing}, unknown {extra}")
    return Material(str(d["name"]), check_range("material E", d["E"], 1.0, 1e7, "MPa"),
                    check_range("material nu", d["nu"]), check_range("material sigma_u", d["sigma_u"], 0.01, 1e5, "MPa"),
                    check_range("material density", d["density"], 0.0, 1e-7, "t/mm³"))


def table_material(spec: str | dict) -> Material:
    """The material a ``[check].material`` entry names: a library name, or the scene's own table."""
    return get_material(str(spec)) if not isinstance(spec, dict) else material_from_dict(spec)
