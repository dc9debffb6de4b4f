"""The inflo command-line tools (one subpackage per CLI) and their shared numerical cores."""
