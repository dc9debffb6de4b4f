"""fccompose: Floral Canopy Composer: grow the canopy by PBD with continuous collision handling (thesis ch. 3-4).

- :mod:`.model`: the canopy as a constraint system (static ``Model``, changing ``State``), built
  from a ``.fcc`` file with its OBJ sequences, weight files, SCN and RBA files.
  Carved into :mod:`.system` (the constraint system), :mod:`.inputs` (reading the files),
  :mod:`.assemble` (instancing the placements) and :mod:`.kernels` (numba kernels).
- :mod:`.compose`: :func:`compose_canopy`, Algorithm 1 (growth, CCD, collision response) and the
  frame loop; :mod:`.simulation`: :class:`Simulation`, one step at a time with its retries and
  collision rounds; :mod:`.output`: the frames, resume state and fingerprint on disk.
- :mod:`.log`: the per-frame ``log.csv``.
"""
