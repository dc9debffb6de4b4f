"""Golden stage outputs: the golden files of each species' draft build and a
tolerance-aware diff of inflo's stage formats. Doc (tolerances, manifest, refresh):
``tests/golden/README.md``.

- :mod:`~inflo.tools.golden.compare`: how two files are compared (structure exactly, numbers
  within a :class:`Tolerance`, timing columns ignored) and the report of the differences;
- :mod:`~inflo.tools.golden.species`: the species that have goldens (``tests/golden/<species>/
  manifest.toml``: pipeline, make targets, golden files, gzipped ones, tolerances), their builds,
  check and refresh;
- :mod:`~inflo.tools.golden.cli`: the command line, ``python -m inflo.tools.golden check|refresh|diff``
  (usage and exit codes in its docstring).

This is test tooling (``tests/test_golden.py``, ``make golden``, ``make golden-check``), not a
pipeline stage.
"""
from .compare import (
    CHAOTIC,
    DEFAULT,
    MAX_DETAILS,
    MAX_FINDINGS,
    TIMING_COLUMNS,
    FileDiff,
    Finding,
    Tolerance,
    diff_files,
    diff_trees,
    format_report,
)
from .species import (
    Entry,
    Species,
    build_species,
    check_listing,
    check_species,
    find_repo,
    load_species,
    make_command,
    make_env,
    refresh_species,
    species_with_manifest,
)

__all__ = [
    "Tolerance",
    "DEFAULT",
    "CHAOTIC",
    "Finding",
    "FileDiff",
    "MAX_DETAILS",
    "MAX_FINDINGS",
    "TIMING_COLUMNS",
    "diff_files",
    "diff_trees",
    "format_report",
    "Entry",
    "Species",
    "find_repo",
    "load_species",
    "species_with_manifest",
    "check_listing",
    "check_species",
    "refresh_species",
    "build_species",
    "make_command",
    "make_env",
]
