"""``canopy-view``: the viewer page of a build (``page.py`` writes it, ``cli.py`` serves it,
``notebook.py`` embeds it in Jupyter); formats/gltf.md."""
