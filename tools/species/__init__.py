"""What the species builds share (formats/species.md).

``python -m inflo.tools.species``: ``list`` prints every species of ``pipelines/`` with one line
each (``make species``); ``vars`` writes one species' settings at a quality as make variables
(``pipelines/species.mk``). The modules the species' own scripts import: :mod:`.checks` (the
shared check report), :mod:`.keys` (key-pose builders), :mod:`.weights` (weight files, also
``python -m inflo.tools.species.weights``). This file imports nothing: make runs ``vars`` each
time it reads a species Makefile.
"""
