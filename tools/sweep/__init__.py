"""``inflo-sweep``: variants and parameter sweeps of a pipeline or of CLI stages on Dask.

- :mod:`.spec` reads a sweep file (formats/sweep.md) into frozen dataclasses and generates its
  variants (a grid, or random samples with a seed);
- :mod:`.overrides` writes a variant's inputs: TOML keys, ``.fcc`` ``key: value`` lines, CLI flags;
- :mod:`.variant` runs one variant (worker side): its stages in-process or ``make`` on a copy of a
  pipeline, its metrics, its ``done`` marker;
- :mod:`.results` writes ``results.csv``, the contact sheet and the heat map;
- :mod:`.sweep` runs the variants as Dask tasks on a ``LocalCluster`` or a scheduler address;
- :mod:`.cli` is the click front end.
"""
