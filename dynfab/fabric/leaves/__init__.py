"""Fabric leaves, one behaviour per file: goals, orientations, obstacles, shapes, limits, self-collision."""
