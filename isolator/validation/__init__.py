"""Independent checks of the model: the MuJoCo multibody build of a scenario."""
