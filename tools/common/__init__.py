"""Shared pieces of every CLI: error handling, progress bars."""
