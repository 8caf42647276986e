"""rigfem: finite-element stress checker for the configurable-bar linkage rig.

Data path, one module per step::

    scene -> linkage/mechanisms (reactions) -> loadcases -> parts/mesh -> fe -> verdict -> report
"""

__version__ = "0.1.0"
