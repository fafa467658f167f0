"""prsc: a compiler for probabilistic 3D scene specifications for robot manipulation."""
