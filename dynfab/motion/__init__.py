"""Motion references: trajectories, safe expressions, global paths."""
