"""What the planner knows of the scene: surfaces (meshes) as nearest points per robot sphere."""
