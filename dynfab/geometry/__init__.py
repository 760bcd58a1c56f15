"""Shapes and distances: obstacle shapes, sphere fitting, exact collision checks."""
