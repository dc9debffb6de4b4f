"""branch-gen: Grow the branching structure under the florets (thesis ch. 7) or a space-colonization tree."""
