"""Optimization fabrics: spec algebra, maps, energies, leaves, the root and the planner."""
