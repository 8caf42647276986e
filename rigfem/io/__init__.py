"""Files other programs read or write: CalculiX decks and results, reaction CSVs.

The public API, loaded on first use (``lazy_loader``): importing one name does not
import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "calculix": ["CalculixError", "CcxResult", "write_inp", "export_model", "read_frd", "run_ccx"],
        "reactions_csv": ["write_csv", "read_csv"],
    },
)
