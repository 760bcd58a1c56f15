"""Scenario files shipped with the package (the demo)."""
