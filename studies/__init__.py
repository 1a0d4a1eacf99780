"""Reproducible studies built on the public API of isolator and controllers."""
