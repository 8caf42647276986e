"""Part definitions (TOML, every dimension with its unit and source), installed as ``rigfem.geometry``.

This folder stays at the repository's top level; pyproject.toml maps it into the package so a
regular and an editable install find it the same way (``importlib.resources``).
"""
