"""The symbolic model: the Newton-Euler residual, isolator elements, variants, equilibrium, the built-model cache."""
