"""Plots of runs and experiment series."""
