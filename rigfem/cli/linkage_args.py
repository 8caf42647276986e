"""The options that name a linkage, shared by the commands that take one (reactions, kinematics),
and the one --allow-rule-violations of the commands that judge a rig configuration's strength."""

from __future__ import annotations

import argparse

from rigfem.cli.exitcodes import RULES_REFUSED
from rigfem.errors import check_range
from rigfem.settings import REFERENCE_SCENE

def lengths(names: tuple[str, ...], values: list[str]) -> list[float]:
    """--four-bar / --slider-crank lengths as positive floats (InputError naming the one that is
    not); the builders then hold them to 10-10000 mm, saying when a length looks like metres."""
    return [check_range(n, v, 0.0, None, "mm", lo_open=True) for n, v in zip(names, values)]


def add_linkage_arguments(p: argparse.ArgumentParser) -> None:
    """SCENE, or --four-bar B2 B3 B4 D / --slider-crank B2 B3 [--offset E] (mm)."""
    p.add_argument("scene", nargs="?", help=f"scene file (TOML with a [linkage] table) or built-in scene name "
                                            f"(default {REFERENCE_SCENE}, the same as rigfem check's, unless "
                                            f"--four-bar or --slider-crank is given)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--four-bar", nargs=4, metavar=("B2", "B3", "B4", "D"),
                   help="four-bar crank, coupler, rocker, ground lengths (mm)")
    g.add_argument("--slider-crank", nargs=2, metavar=("B2", "B3"), help="slider-crank crank and rod (mm)")
    p.add_argument("--offset", metavar="E", help="slider-crank slide-line offset (mm, default 0)")


def add_rule_argument(p: argparse.ArgumentParser) -> None:
    """--allow-rule-violations, with the one rule (:data:`rigfem.cli.exitcodes.RULES_REFUSED`)."""
    p.add_argument("--allow-rule-violations", action="store_true", help=RULES_REFUSED)
