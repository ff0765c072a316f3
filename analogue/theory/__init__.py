"""Theory of the stick-slip model: weak-noise (the paper) and exact finite-noise numerics."""
