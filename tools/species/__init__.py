"""``python -m inflo.tools.species``: the species files as the build sees them (formats/species.md).

``list`` prints every species of ``pipelines/`` with one line each (``make species``); ``vars``
writes one species' settings at a quality as make assignments (``pipelines/species.mk``).
"""
