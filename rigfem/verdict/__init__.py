"""The verdict on a part: σu/2 criterion with its error band, Goodman fatigue.

The public API, loaded on first use (``lazy_loader``): importing one name does not
import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "criterion": ["Verdict", "LIMIT_FACTOR", "IMBALANCE_TOL", "allowable_stress", "half_ultimate", "overall"],
        "fatigue": ["Marin", "marin_endurance", "goodman"],
        "part": ["Outcome", "PartVerdict", "Verdicts", "Target", "judge"],
    },
)
