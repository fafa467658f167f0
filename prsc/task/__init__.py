"""The task of a spec (docs/tasks.md): its compiled form as plain data, and one evaluator of
it on a world state (poses, velocities, distances) that knows no simulator."""
