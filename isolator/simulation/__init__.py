"""Transient simulation: the simulator, batches, responses and settling metrics."""
