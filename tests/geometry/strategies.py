"""Shared strategies and helpers for the geometry tests."""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

angles = st.floats(-np.pi, np.pi, allow_nan=False)
unit_quats = st.tuples(*[st.floats(-1, 1) for _ in range(4)]).filter(
    lambda q: 0.1 < float(np.linalg.norm(q))
).map(lambda q: np.asarray(q) / np.linalg.norm(q))
rotations = unit_quats.map(lambda q: Rotation.from_quat(q, scalar_first=True).as_matrix())
half_extents = st.tuples(*[st.floats(0.01, 1.0) for _ in range(3)]).map(np.asarray)
points = st.tuples(*[st.floats(-2.0, 2.0) for _ in range(3)]).map(np.asarray)
