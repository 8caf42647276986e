"""The rig sweep: every rig configuration's rules, reactions and stress verdicts.

Loaded on first use (``lazy_loader``): importing one name does not import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "configs": ["SweepParams", "enumerate_configs"],
        "bases": ["build_bases"],
        "superpose": ["case_peak"],
        "run": ["evaluate", "run_chunk", "run_sweep", "SweepOptions"],
        "report": ["write_report"],
        "cost": ["JobCost", "check_cost", "sweep_cost", "synthesis_cost"],
    },
)
