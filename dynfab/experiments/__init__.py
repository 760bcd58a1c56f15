"""The paper's experiments: scenario distributions, the registry and the series runner."""
