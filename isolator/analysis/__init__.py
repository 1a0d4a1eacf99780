"""Linear analyses about rest configurations: linearisation, modes, transmissibility, stability, vibration criteria."""
