"""fccompose: Floral Canopy Composer: grow the canopy by PBD with continuous collision handling (thesis ch. 3-4).

- :mod:`.model`: the canopy as a constraint system (static ``Model``, changing ``State``), built
  from a ``.fcc`` file with its OBJ sequences, weight files, SCN and RBA files.
- :mod:`.compose`: :func:`compose_canopy`, Algorithm 1 (growth, CCD, collision response), output
  frames, log and resume; :class:`Simulation` for one step at a time.
- :mod:`.log`: the per-frame ``log.csv``.
"""
