"""``petal-grow``: opening flowers grown by growth maps (Ijiri, Yokoo, Kawabata, Igarashi, *Surface-based
Growth Simulation for Opening Flowers*, GI 2008).

- :mod:`.maps`: growth maps (PNG or functions of (u, v)), eq. 1.
- :mod:`.growth`: regional growth kernel, eqs. 2-4 (sec. 4).
- :mod:`.bud`: bud meshes with uv (OBJ ``vt``).
- :mod:`.params`: the TOML parameter file (formats/petal_grow.md).
- :mod:`.simulate`: the loop of fig. 6 (growth, PBD global shape, shape-matching attachment,
  collisions, keyframes).
- :mod:`.cli`: the command line.
"""
