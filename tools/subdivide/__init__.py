"""subdivide: Loop subdivision that stays collision-free (thesis 4.4)."""
