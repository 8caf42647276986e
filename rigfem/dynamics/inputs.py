"""What a script hands :func:`rigfem.dynamics.simulate` in place of a Linkage, judged once here
(a boundary module, as :mod:`rigfem.fe.inputs` is for the FE): the dynamics inside trusts it."""

from __future__ import annotations

from rigfem.errors import InputError
from rigfem.linkage.mechanisms import BUILDERS
from rigfem.linkage.model import Linkage


def linkage_of(config: dict) -> Linkage:
    """The Linkage of ``{"type": "four-bar", "b2": .., ...}`` (the builder's keyword arguments, mm);
    InputError naming the type when it is not one of :data:`rigfem.linkage.mechanisms.BUILDERS`."""
    cfg = dict(config)
    typ = cfg.pop("type", None)
    if typ not in BUILDERS:
        raise InputError(f"linkage type = {typ!r} must be one of {', '.join(BUILDERS)}")
    return BUILDERS[typ](**cfg)
