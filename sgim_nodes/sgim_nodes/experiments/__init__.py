"""Pinned experiments: the files under experiments/ that make every published figure."""
