"""The typed IR: what the front end hands to the constraint stage.

Contract between prsc/ir (producer) and prsc/constraints + prsc/sampling (consumers).
Every node is a frozen dataclass carrying the source span it came from. Names are
resolved (no bare identifiers remain), class defaults are instantiated per object
(`self.prop` becomes PropertyRef(ObjectRef(<this object>), prop)), imports are inlined,
and every expression has a static type.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from prsc.user_assets.asset_links import AssetLink
from prsc.errors import Span


class Type(enum.Enum):
    """Static types of IR expressions."""

    SCALAR = "scalar"
    VECTOR = "vector"
    ORIENTED_POINT = "oriented point"  # a face point: a position carrying an orientation
    OBJECT = "object"
    REGION = "region"
    STRING = "string"
    BOOL = "bool"
    LIST = "list"
    ANY = "any"  # e.g. Uniform over mixed values; checked at sampling time


# ---------------------------------------------------------------- expressions


@dataclass(frozen=True)
class Expr:
    """Base of all expressions."""

    span: Span
    type: Type


@dataclass(frozen=True)
class Const(Expr):
    """A literal number, string or bool."""

    value: float | str | bool


@dataclass(frozen=True)
class VectorExpr(Expr):
    """`Vector3D(x, y, z)` / `V3D(...)`."""

    x: Expr
    y: Expr
    z: Expr


@dataclass(frozen=True)
class ListExpr(Expr):
    """`[a, b, ...]`."""

    items: tuple[Expr, ...]


@dataclass(frozen=True)
class ObjectRef(Expr):
    """A scene object, by its IR name (anonymous objects have generated names)."""

    name: str


@dataclass(frozen=True)
class VarRef(Expr):
    """A global variable (Program.variables); a random one is drawn once per scene."""

    name: str


@dataclass(frozen=True)
class PropertyRef(Expr):
    """`target.prop`: object property, `.x/.y/.z` of a vector or position, `point.position`."""

    target: Expr
    prop: str


@dataclass(frozen=True)
class FacePoint(Expr):
    """`top back X` etc.: words are a subset of {top,bottom}, {front,back}, {left,right}."""

    target: Expr
    words: tuple[str, ...]


@dataclass(frozen=True)
class RelativeTo(Expr):
    """`V relative to X`: X.position + R_X·V for an object X, X + V for a vector."""

    value: Expr
    frame: Expr


@dataclass(frozen=True)
class Distance(Expr):
    """`distance from A to B`: the Euclidean distance between two points (an object's is
    its centre, a face point's its position); docs/language.md, "distance from X to Y"."""

    source: Expr
    target: Expr


@dataclass(frozen=True)
class BinOp(Expr):
    """Arithmetic `+ - * /` on scalars and vectors."""

    op: str
    left: Expr
    right: Expr


@dataclass(frozen=True)
class UnaryOp(Expr):
    """Unary `-`, `+` and `not`."""

    op: str
    operand: Expr


@dataclass(frozen=True)
class Compare(Expr):
    """`a < b`, `<=`, `>`, `>=`, `==`, `!=` (a chain is lowered to an `and` of pairs)."""

    op: str
    left: Expr
    right: Expr


@dataclass(frozen=True)
class BoolOp(Expr):
    """`and` / `or` over two or more operands."""

    op: str
    operands: tuple[Expr, ...]


@dataclass(frozen=True)
class Call(Expr):
    """A pure math function: sin cos tan sqrt abs min max hypot atan2."""

    func: str
    args: tuple[Expr, ...]


@dataclass(frozen=True)
class Distribution(Expr):
    """A random value, drawn per scene.

    kind: "range" (args low, high), "normal" (mean, sd), "truncnormal" (mean, sd, low,
    high), "uniform" (args are the options), "discrete" (args options, weights weights).
    draw_id is unique in the Program: two textually equal distributions are distinct
    draws, and one class default instantiated for two objects gives two draw_ids.
    """

    kind: str
    args: tuple[Expr, ...]
    draw_id: int
    weights: tuple[Expr, ...] = ()


@dataclass(frozen=True)
class RegionExpr(Expr):
    """A region constructor with its arguments normalised by name.

    kind and args:
      "cuboid": position, orientation, width, length, height
      "rectangle": position, orientation, width, length   (a planar rectangle)
      "halfspace": point, normal, dist (dist defaults to Const(0))
      "polygon": vertices (ListExpr of vectors)
      "polyhedron": vertices (ListExpr of vectors)
      "intersection": regions (ListExpr of regions)
      "all", "empty": no args
    orientation args are VectorExpr of compat Euler angles (docs/language.md, `with orientation`).
    """

    kind: str
    args: tuple[tuple[str, Expr], ...]

    def arg(self, name: str) -> Expr:
        """The argument called name."""
        return dict(self.args)[name]


@dataclass(frozen=True)
class SurfaceRef(Expr):
    """`X.name[index]`: support surface `index` of the list `name` that X's class declares
    in its `surfaces` (docs/language.md, "Support surfaces"); a planar region."""

    target: Expr
    name: str
    index: Expr


@dataclass(frozen=True)
class LinkRef(Expr):
    """`X.links["NAME"]`: link NAME of X's URDF or MJCF asset at the scene's joint values, a
    target of `on` and `in` (docs/assets.md, "Links"). `link` (the chain to it and its
    collision boxes) and `root_offset` (the asset's root in X's box) are read from the file
    by ir/asset_models.py."""

    target: Expr
    name: str
    link: AssetLink | None = None
    root_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)


# ---------------------------------------------------------------- specifiers


@dataclass(frozen=True)
class Specifier:
    """Base of all specifiers: what it sets and which of its own object's properties it reads."""

    span: Span
    sets: tuple[str, ...]  # properties this specifier determines, e.g. ("position",)
    reads: tuple[str, ...]  # properties of the same object it needs first, e.g. ("orientation", "width")
    # True on a position specifier that must erode with the orientation-free bound (the
    # radius of the footprint) because the object's orientation depends on its position
    # (`facing toward`); "orientation" is then absent from reads (added by the front end).
    orientation_free: bool = field(default=False, kw_only=True)


@dataclass(frozen=True)
class With(Specifier):
    """`with prop value`."""

    prop: str
    value: Expr


@dataclass(frozen=True)
class At(Specifier):
    """`at V` (a `relative to` is already folded into V as RelativeTo)."""

    point: Expr


@dataclass(frozen=True)
class Beyond(Specifier):
    """`beyond X by d from P` (d scalar or vector)."""

    target: Expr
    by: Expr
    origin: Expr


@dataclass(frozen=True)
class In(Specifier):
    """`[completely] in R`."""

    region: Expr
    completely: bool


@dataclass(frozen=True)
class On(Specifier):
    """`[completely] on X`, X an object, a planar region or a vector/point.

    `inside`: written `[completely] in X` for an object X, which means X's container interior.
    """

    target: Expr
    completely: bool
    inside: bool = field(default=False, kw_only=True)


@dataclass(frozen=True)
class Direction(Specifier):
    """`left of X [by d]` etc.; relation in left/right/ahead/behind/above/below.

    by is the least gap (None: 0); up_to, from `by (low, high)`, the greatest (None: no bound).
    """

    relation: str
    target: Expr
    by: Expr | None
    up_to: Expr | None = None


@dataclass(frozen=True)
class AlignedWith(Specifier):
    """`aligned with X on x|y|z` / `by "x"`."""

    target: Expr
    axis: str


@dataclass(frozen=True)
class Facing(Specifier):
    """`facing V` (vector: smallest rotation of +y onto V) or `facing θ` (scalar yaw)."""

    direction: Expr


@dataclass(frozen=True)
class FacingToward(Specifier):
    """`facing toward P`: yaw-only, local +y horizontally at P."""

    target: Expr


@dataclass(frozen=True)
class ReachableBy(Specifier):
    """`reachable by R`: the centre inside robot R's top-down reachable set (docs/sampling.md)."""

    robot: Expr


@dataclass(frozen=True)
class StablyOn(Specifier):
    """`stably on X`: on X, with the centre of mass of everything stacked over each support
    (X, what X stands stably on, ...) over that support's top face (docs/language.md)."""

    target: Expr


@dataclass(frozen=True)
class VisibleFrom(Specifier):
    """`visible from C`: the box inside camera C's view frustum; `outside` (written `not visible
    from C`): the box not wholly inside it (docs/language.md)."""

    camera: Expr
    outside: bool = field(default=False, kw_only=True)
