"""``canopy-view``: the viewer page of a build (``page.py`` writes it, ``cli.py`` serves it); formats/gltf.md."""
