"""``canopy-export``: OBJ sequences + a colour file -> one USD growth animation (and PC2 caches).

Modules: :mod:`.parts` (the inputs: named OBJ sequences, read frame by frame with their topology
checked), :mod:`.usd` (the USD stage writer, ``usd-core``), :mod:`.export` (``export_canopy``, the
library function), :mod:`.cli` (the command). Spec of the output: ``formats/usd.md``.
"""
