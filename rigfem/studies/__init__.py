"""Deprecated: ``rigfem.studies`` was split by what it holds (0.2): the sweep is
:mod:`rigfem.sweep`, the verification studies :mod:`rigfem.verification` and the rig design
:mod:`rigfem.design`.  Every old name and module still imports from here, with a
DeprecationWarning naming its new home; this alias goes in 0.3.
"""
import importlib
import importlib.abc
import importlib.util
import sys
import warnings

#: old module -> its new home
MODULES = {'band_coverage': 'verification.band_coverage',
           'cost': 'sweep.cost',
           'closed_form': 'verification.closed_form',
           'convergence': 'verification.convergence',
           'le10': 'verification.le10',
           'sweep_configs': 'sweep.configs',
           'sweep_bases': 'sweep.bases',
           'sweep': 'sweep.run',
           'shapes': 'verification.shapes',
           'sweep_report': 'sweep.report',
           'rig_design': 'design.rig_design',
           'verify': 'verification.calculix',
           'explorer': 'sweep.explorer'}

#: old name (``from rigfem.studies import X``) -> the module that holds it now
NAMES = {
    'AWAY_MM': 'verification.convergence',
    'BOUND_GROUPS': 'sweep.configs',
    'BYTES_PER_ANGLE': 'sweep.cost',
    'CALIBRATION_SIZES': 'verification.band_coverage',
    'CLOSED_FORMS': 'verification.band_coverage',
    'CONNECT_TIMEOUT_S': 'sweep.run',
    'Comparison': 'verification.calculix',
    'EXTEND': 'verification.convergence',
    'Extrapolation': 'verification.convergence',
    'FACES': 'verification.shapes',
    'FINAL_DESIGN': 'sweep.report',
    'GROUND_RAIL_MM': 'sweep.configs',
    'HALF_THICKNESS': 'verification.le10',
    'H_DIRECTIONS': 'verification.convergence',
    'INNER': 'verification.le10',
    'JOINTS': 'sweep.configs',
    'JobCost': 'sweep.cost',
    'LENGTHS': 'sweep.configs',
    'LENGTH_KEYS': 'design.rig_design',
    'NOISE': 'verification.convergence',
    'ORIGINAL_DIRECTIONS': 'sweep.configs',
    'OUTER': 'verification.le10',
    'PARTS': 'verification.band_coverage',
    'PART_CALIBRATION_STEPS': 'verification.band_coverage',
    'POINT_D': 'verification.le10',
    'PRESETS': 'verification.band_coverage',
    'PRESSURE': 'verification.le10',
    'RATIO': 'verification.convergence',
    'ROW_CHUNK': 'sweep.configs',
    'SECONDS_PER_ANGLE': 'sweep.cost',
    'STEEL': 'verification.le10',
    'SURFACES': 'verification.le10',
    'StepSpec': 'verification.convergence',
    'SweepParams': 'sweep.configs',
    'TARGETS': 'verification.convergence',
    'TARGET_SYY': 'verification.le10',
    'TOP_NODES': 'sweep.configs',
    'TYPES': 'sweep.configs',
    'UnitBasis': 'sweep.bases',
    'WORST': 'sweep.report',
    'analyse': 'verification.convergence',
    'away_from_singular_edges': 'verification.convergence',
    'bar_with_holes': 'verification.shapes',
    'bases_cost': 'sweep.cost',
    'box': 'verification.shapes',
    'build_bases': 'sweep.bases',
    'calibrate': 'verification.band_coverage',
    'case_key': 'sweep.bases',
    'case_peak': 'sweep.superpose',
    'check_cost': 'sweep.cost',
    'check_scheduler': 'sweep.run',
    'closed_form_case': 'verification.band_coverage',
    'compare': 'verification.calculix',
    'coverage': 'verification.band_coverage',
    'cross_check': 'verification.calculix',
    'enumerate_configs': 'sweep.configs',
    'evaluate': 'sweep.run',
    'faces_at': 'verification.shapes',
    'fine_step': 'verification.convergence',
    'gmsh_part': 'verification.shapes',
    'h_levels': 'verification.convergence',
    'inside': 'verification.band_coverage',
    'kt_plate_hole': 'verification.closed_form',
    'le10_mesh': 'verification.le10',
    'load': 'verification.le10',
    'markdown': 'verification.band_coverage',
    'mesh_ahead': 'sweep.bases',
    'needs_finer': 'verification.convergence',
    'node_at': 'verification.le10',
    'part_cases': 'verification.band_coverage',
    'plate_hole_peak_mpa': 'verification.closed_form',
    'plate_with_hole': 'verification.shapes',
    'preset_mesh': 'verification.band_coverage',
    'preset_steps': 'verification.convergence',
    'quarter_ring': 'verification.shapes',
    'rail_lengths': 'sweep.configs',
    'reach_scheduler': 'sweep.run',
    'required_factor': 'verification.band_coverage',
    'richardson': 'verification.convergence',
    'rig_fourbars': 'design.rig_design',
    'rig_rail_layout': 'sweep.configs',
    'rule_table': 'design.rig_design',
    'rules_row': 'sweep.configs',
    'run': 'verification.band_coverage',
    'run_chunk': 'sweep.run',
    'run_step': 'verification.convergence',
    'run_sweep': 'sweep.run',
    'scene_cases': 'verification.convergence',
    'snap_function': 'design.rig_design',
    'snap_motion': 'design.rig_design',
    'solve_le10': 'verification.le10',
    'stress_verdicts': 'design.rig_design',
    'study': 'verification.convergence',
    'summary_html': 'sweep.report',
    'superposed_peaks': 'sweep.superpose',
    'supports': 'verification.le10',
    'sweep_cost': 'sweep.cost',
    'synthesis_cost': 'sweep.cost',
    'to_json': 'verification.convergence',
    'turning': 'sweep.cost',
    'worst_markdown': 'sweep.report',
    'write_maps': 'sweep.report',
    'write_report': 'sweep.report',
}

__all__ = sorted(NAMES)


def _warn(old: str, new: str) -> None:
    warnings.warn(f"{old} moved to {new}; the old name goes in rigfem 0.3", DeprecationWarning, stacklevel=3)


def __getattr__(name: str):
    if name in NAMES:
        _warn(f"rigfem.studies.{name}", f"rigfem.{NAMES[name]}.{name}")
        value = globals()[name] = getattr(importlib.import_module(f"rigfem.{NAMES[name]}"), name)
        return value  # once: a from-import asks twice
    if name in MODULES:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class _Alias(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """``import rigfem.studies.X``: the module's new home, under its old name too."""

    def find_spec(self, fullname, path=None, target=None):
        head, _, tail = fullname.rpartition(".")
        if head == __name__ and tail in MODULES:
            return importlib.util.spec_from_loader(fullname, self)
        return None

    def create_module(self, spec):
        tail = spec.name.rpartition(".")[2]
        _warn(spec.name, f"rigfem.{MODULES[tail]}")
        return importlib.import_module(f"rigfem.{MODULES[tail]}")

    def exec_module(self, module) -> None:
        pass


if not any(isinstance(f, _Alias) for f in sys.meta_path):
    sys.meta_path.insert(0, _Alias())
