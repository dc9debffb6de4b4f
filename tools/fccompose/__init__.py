"""fccompose: Floral Canopy Composer: grow the canopy by PBD with continuous collision handling (thesis ch. 3-4)."""
