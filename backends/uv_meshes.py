"""Unit primitives as USD meshes with texture coordinates (`primvars:st`), for `with
texture` on a box, cylinder or sphere: UsdGeom's Cube, Cylinder and Sphere have no UVs to
show an image through. Each fills the unit cube centred at its origin, so a part's size is
its scale. The box shows the whole image on every face; the cylinder wraps it once round
its side (u along the angle, v up) and shows it on each cap; the sphere wraps it as
longitude and latitude. MJCF needs none of this: MuJoCo maps a cube texture onto any
primitive (backends/mjcf.py)."""

from __future__ import annotations

import math

SEGMENTS = 32  # around the cylinder's axis and the sphere's
RINGS = 16  # from the sphere's south pole to its north pole

_BOX_FACES = (  # each face of the unit box: its corners counter-clockwise seen from outside
    ((1, -1, -1), (1, 1, -1), (1, 1, 1), (1, -1, 1)), ((-1, 1, -1), (-1, -1, -1), (-1, -1, 1), (-1, 1, 1)),
    ((1, 1, -1), (-1, 1, -1), (-1, 1, 1), (1, 1, 1)), ((-1, -1, -1), (1, -1, -1), (1, -1, 1), (-1, -1, 1)),
    ((-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)), ((-1, 1, -1), (1, 1, -1), (1, -1, -1), (-1, -1, -1)),
)

Face = tuple[tuple[float, float, float], ...]  # corners, counter-clockwise seen from outside
Corners = tuple[tuple[float, float], ...]  # the texture coordinate of each corner


def _box() -> list[tuple[Face, Corners]]:
    square = ((0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0))
    return [(tuple(tuple(0.5 * c for c in corner) for corner in face), square) for face in _BOX_FACES]


def _cylinder() -> list[tuple[Face, Corners]]:
    faces = []
    ring = [(0.5 * math.cos(2 * math.pi * j / SEGMENTS), 0.5 * math.sin(2 * math.pi * j / SEGMENTS)) for j in range(SEGMENTS + 1)]
    for j in range(SEGMENTS):
        (x0, y0), (x1, y1) = ring[j], ring[j + 1]
        u0, u1 = j / SEGMENTS, (j + 1) / SEGMENTS
        faces.append((((x0, y0, -0.5), (x1, y1, -0.5), (x1, y1, 0.5), (x0, y0, 0.5)), ((u0, 0.0), (u1, 0.0), (u1, 1.0), (u0, 1.0))))
    top = tuple((x, y, 0.5) for x, y in ring[:-1])
    faces.append((top, tuple((x + 0.5, y + 0.5) for x, y, _ in top)))
    bottom = tuple((x, y, -0.5) for x, y in reversed(ring[:-1]))
    faces.append((bottom, tuple((x + 0.5, 0.5 - y) for x, y, _ in bottom)))
    return faces


def _sphere() -> list[tuple[Face, Corners]]:
    def point(i: int, j: int) -> tuple[float, float, float]:
        polar, azimuth = math.pi * i / RINGS, 2 * math.pi * j / SEGMENTS
        return (0.5 * math.sin(polar) * math.cos(azimuth), 0.5 * math.sin(polar) * math.sin(azimuth), -0.5 * math.cos(polar))

    faces = []
    for i in range(RINGS):
        for j in range(SEGMENTS):
            corners = [(i, j), (i, j + 1), (i + 1, j + 1), (i + 1, j)]
            if i == 0:
                corners.pop(1)  # the south pole: one corner, not two
            elif i == RINGS - 1:
                corners.pop(2)  # the north pole
            faces.append((tuple(point(a, b) for a, b in corners), tuple((b / SEGMENTS, a / RINGS) for a, b in corners)))
    return faces


SHAPES = {"box": _box, "cylinder": _cylinder, "sphere": _sphere}


def unit_uv_mesh(stage, path: str, shape: str):
    """A UsdGeom.Mesh at `path`: the unit box, cylinder (axis z) or sphere with `primvars:st` per face corner."""
    from pxr import Gf, Sdf, UsdGeom, Vt

    faces = SHAPES[shape]()
    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.CreatePointsAttr([Gf.Vec3f(*corner) for face, _ in faces for corner in face])
    mesh.CreateFaceVertexCountsAttr([len(face) for face, _ in faces])
    mesh.CreateFaceVertexIndicesAttr(list(range(sum(len(face) for face, _ in faces))))
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    mesh.CreateExtentAttr([Gf.Vec3f(-0.5, -0.5, -0.5), Gf.Vec3f(0.5, 0.5, 0.5)])
    st = Vt.Vec2fArray([Gf.Vec2f(u, v) for _, corners in faces for u, v in corners])
    UsdGeom.PrimvarsAPI(mesh).CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.faceVarying).Set(st)
    return mesh
