"""Pure geometry for prsc: rotations, boxes, H-polytopes, erosion, exact uniform samplers,
oriented-box collision, free-space decomposition, hit-and-run and IIS.

Imports nothing of prsc outside this package (numpy, scipy, highspy only). Each module's
docstring describes its part of the API; docs/sampling.md how the sampler uses them.
"""

from __future__ import annotations

from prsc.geometry.affine import TOL, AffineRegion, reduce_affine
from prsc.geometry.boxes import Box, support
from prsc.geometry.exceptions import EmptyRegionError, GeometryError, UnboundedRegionError
from prsc.geometry.free_space import FreeSpace, free_space, free_space_sampler
from prsc.geometry.hit_and_run import hit_and_run
from prsc.geometry.iis import irreducible_infeasible_subset, is_feasible
from prsc.geometry.lp import chebyshev_center, solve_lp
from prsc.geometry.obb import (
    CONTACT_TOL,
    boxes_collide,
    collides_many,
    minkowski_obstacle,
    penetration,
)
from prsc.geometry.polytope import NO_LABEL, Polytope, erode_by_box, intersect
from prsc.geometry.rotations import (
    compat_euler_to_matrix,
    matrix_to_quat,
    matrix_to_rpy,
    quat_to_matrix,
    quat_to_rpy,
    rot_x,
    rot_y,
    rot_z,
    rotation_taking_y_to,
    rpy_to_matrix,
    rpy_to_quat,
    yaw_matrix,
    yaw_toward,
)
from prsc.geometry.uniform_sampling import UniformSampler, prepare_sampler, union_sampler

__all__ = [
    "TOL", "AffineRegion", "reduce_affine",
    "Box", "support",
    "EmptyRegionError", "GeometryError", "UnboundedRegionError",
    "FreeSpace", "free_space", "free_space_sampler",
    "hit_and_run",
    "irreducible_infeasible_subset", "is_feasible",
    "chebyshev_center", "solve_lp",
    "CONTACT_TOL", "boxes_collide", "collides_many", "minkowski_obstacle", "penetration",
    "NO_LABEL", "Polytope", "erode_by_box", "intersect",
    "compat_euler_to_matrix", "matrix_to_quat", "matrix_to_rpy", "quat_to_matrix",
    "quat_to_rpy", "rot_x", "rot_y", "rot_z", "rotation_taking_y_to", "rpy_to_matrix",
    "rpy_to_quat", "yaw_matrix", "yaw_toward",
    "UniformSampler", "prepare_sampler", "union_sampler",
]
