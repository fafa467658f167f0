"""The task of a spec (LANGUAGE.md section 8): its compiled form as plain data, and one evaluator of
it on a world state (poses, velocities, distances) that knows no simulator."""
