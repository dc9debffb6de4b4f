"""dimorph: Set floret types and sizes by cones (thesis ch. 6)."""
