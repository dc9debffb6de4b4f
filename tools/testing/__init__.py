"""Test support: synthetic meshes and scenes for the tests, the benchmarks and the examples.

Nothing here is a pipeline stage or follows the thesis's models; the tools never import it.

- :mod:`.flowers`: curved open petal patches, flowers and canopies (cheap meshes with what matters
  to a renderer: open surfaces seen from both sides, overlapping petals, several materials).
- :mod:`.florets`: opening florets as OBJ sequences with weight files, and ``.fcc`` scenes of them
  (two florets, a grid canopy) for fccompose.
"""
