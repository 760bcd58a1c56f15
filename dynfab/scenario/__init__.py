"""The scenario file contract: schema, references, controllers, runner, metrics."""
