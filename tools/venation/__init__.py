"""venation: leaf venation patterns by space colonization, open and closed (Runions ch. 4)."""
