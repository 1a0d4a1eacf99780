"""Inputs to the table: profile design, feedforward and feedback (later issues)."""
