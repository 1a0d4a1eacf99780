"""Scenarios: reading TOML, validation, the frozen dataclasses, motion profiles."""
