"""Command-line tools that build the world's data files (mapping, benchmark set, teaching set)."""
