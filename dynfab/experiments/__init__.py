"""The paper's experiments: scenario distributions (and, later, the runner)."""
