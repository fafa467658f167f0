"""USD backend: one stage per scene (usda text), UsdPhysics throughout.

Stage: Z up, metersPerUnit 1, kilogramsPerUnit 1, default prim `/World` holding a
PhysicsScene, the ground (a plane collider) and an Xform per object named after it at the
scene pose (translate + orient, double precision). A rigid object is a body with
RigidBodyAPI and MassAPI (static objects are kinematic bodies, which the simulation never
moves) whose parts are UsdGeom gprims with CollisionAPI. A camera object holds a
UsdGeom.Camera `camera` looking along the object's +y (a USD camera looks along its -Z
with +Y up). A Robot references the robot's articulation asset from the store under
`<object>/mount` (the bottom centre of its box, yawed so the arm reaches along +y) and sets
the world-side frame of the asset's `root_joint` to that mount.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from prsc.assets.articulated import robot_tree
from prsc.backends.bodies import CAMERA_QUAT_NEG_Z, Body, object_matrix, resolve_bodies
from prsc.backends.scene import GROUND_HALF_SIZE, Scene
from prsc.backends.store import AssetStore, relative_path
from prsc.backends.uv_meshes import unit_uv_mesh
from prsc.geometry.rotations import matrix_to_quat, rot_z

CAMERA_VERTICAL_APERTURE = 20.955  # mm, USD's default; the focal length sets the fov


def _gf_quatd(q):
    from pxr import Gf

    return Gf.Quatd(float(q[0]), Gf.Vec3d(float(q[1]), float(q[2]), float(q[3])))


def _pose(xformable, position, quaternion) -> None:
    from pxr import Gf, UsdGeom

    xformable.AddTranslateOp(UsdGeom.XformOp.PrecisionDouble).Set(Gf.Vec3d(*(float(v) for v in position)))
    xformable.AddOrientOp(UsdGeom.XformOp.PrecisionDouble).Set(_gf_quatd(quaternion))


def _color(gprim, rgba) -> None:
    from pxr import Gf

    gprim.CreateDisplayColorAttr([Gf.Vec3f(*(float(c) for c in rgba[:3]))])
    gprim.CreateDisplayOpacityAttr([float(rgba[3])])


def _part_prim(stage, path: str, part, folder: Path, rgba, references: list[tuple[str, str]]):
    """A gprim for one part, placed and sized in its body's frame (a mesh's reference to its
    layer is appended to `references`, authored once the stage is closed)."""
    from pxr import Gf, UsdGeom, UsdPhysics

    if part.texture is not None and part.shape != "mesh":
        gprim = unit_uv_mesh(stage, path, part.shape)  # a Cube, Cylinder or Sphere has no UVs to show an image through
        scale = part.size
    elif part.shape == "box":
        gprim = UsdGeom.Cube.Define(stage, path)
        gprim.CreateSizeAttr(1.0)
        gprim.CreateExtentAttr([Gf.Vec3f(-0.5, -0.5, -0.5), Gf.Vec3f(0.5, 0.5, 0.5)])
        scale = part.size
    elif part.shape == "cylinder":
        gprim = UsdGeom.Cylinder.Define(stage, path)
        r, h = part.radius, part.size[2]
        gprim.CreateRadiusAttr(r)
        gprim.CreateHeightAttr(h)
        gprim.CreateAxisAttr(UsdGeom.Tokens.z)
        gprim.CreateExtentAttr([Gf.Vec3f(-r, -r, -h / 2), Gf.Vec3f(r, r, h / 2)])
        scale = None
    elif part.shape == "sphere":
        gprim = UsdGeom.Sphere.Define(stage, path)
        r = part.radius
        gprim.CreateRadiusAttr(r)
        gprim.CreateExtentAttr([Gf.Vec3f(-r, -r, -r), Gf.Vec3f(r, r, r)])
        scale = None
    else:
        gprim = UsdGeom.Mesh.Define(stage, path)
        references.append((path, relative_path(_mesh_usd(part.mesh), folder)))
        scale = part.size
    _pose(gprim, part.position, part.quaternion)
    if scale is not None:
        gprim.AddScaleOp(UsdGeom.XformOp.PrecisionDouble).Set(Gf.Vec3d(*(float(s) for s in scale)))
    _color(gprim, rgba)
    if part.texture is not None:
        from pxr import UsdShade

        UsdShade.MaterialBindingAPI.Apply(gprim.GetPrim()).Bind(_texture_material(stage, part.texture, folder, part.maps))
    if not part.visible:
        gprim.CreatePurposeAttr(UsdGeom.Tokens.guide)  # collision only: renderers skip guides
    if part.collides:
        UsdPhysics.CollisionAPI.Apply(gprim.GetPrim())
        if isinstance(gprim, UsdGeom.Mesh):
            UsdPhysics.MeshCollisionAPI.Apply(gprim.GetPrim()).CreateApproximationAttr(UsdPhysics.Tokens.convexHull)
    return gprim


def _texture_material(stage, texture: str, folder: Path, maps: tuple[tuple[str, str], ...] = ()):
    """The scene's UsdPreviewSurface material showing `texture` through the mesh's `st` primvar
    (one per image, under /World/Looks; the image path is relative to the scene file), with
    the mesh's normal map and roughness and metallic from its ORM map when it has them."""
    from pxr import Gf, Sdf, Tf, UsdGeom, UsdShade

    path = f"/World/Looks/{Tf.MakeValidIdentifier(Path(texture).stem)}"
    material = UsdShade.Material.Get(stage, path)
    if material:
        return material
    UsdGeom.Scope.Define(stage, "/World/Looks")
    material = UsdShade.Material.Define(stage, path)
    reader = UsdShade.Shader.Define(stage, f"{path}/st")
    reader.CreateIdAttr("UsdPrimvarReader_float2")
    reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("st")
    reader.CreateOutput("result", Sdf.ValueTypeNames.Float2)

    def image_reader(name: str, file: str, colour_space: str):
        image = UsdShade.Shader.Define(stage, f"{path}/{name}")
        image.CreateIdAttr("UsdUVTexture")
        image.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(Sdf.AssetPath(relative_path(file, folder)))
        image.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set(colour_space)
        image.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(reader.ConnectableAPI(), "result")
        return image

    image = image_reader("image", texture, "sRGB")
    image.CreateOutput("rgb", Sdf.ValueTypeNames.Float3)
    surface = UsdShade.Shader.Define(stage, f"{path}/surface")
    surface.CreateIdAttr("UsdPreviewSurface")
    surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(image.ConnectableAPI(), "rgb")
    found = dict(maps)
    if "normal" in found:  # a tangent-space normal in [0, 1] per channel, read as [-1, 1]
        normal = image_reader("normal", found["normal"], "raw")
        normal.CreateInput("scale", Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(2.0, 2.0, 2.0, 1.0))
        normal.CreateInput("bias", Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(-1.0, -1.0, -1.0, 0.0))
        normal.CreateOutput("rgb", Sdf.ValueTypeNames.Float3)
        surface.CreateInput("normal", Sdf.ValueTypeNames.Normal3f).ConnectToSource(normal.ConnectableAPI(), "rgb")
    if "orm" in found:  # glTF's packing: roughness in G, metallic in B
        orm = image_reader("orm", found["orm"], "raw")
        for channel, name in (("g", "roughness"), ("b", "metallic")):
            orm.CreateOutput(channel, Sdf.ValueTypeNames.Float)
            surface.CreateInput(name, Sdf.ValueTypeNames.Float).ConnectToSource(orm.ConnectableAPI(), channel)
    else:
        surface.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(0.8)
    material.CreateSurfaceOutput().ConnectToSource(surface.ConnectableAPI(), "surface")
    return material


def _mesh_usd(obj_path: str) -> Path:
    """A USD layer beside a normalised OBJ holding it as a Mesh default prim (made once); a
    textured mesh also holds its UVs as the `st` primvar."""
    from prsc.backends.store import texture_of
    from prsc.files import atomic_write

    target = Path(obj_path).with_suffix(".usda")
    if not target.is_file():
        from prsc.user_assets.mesh_paths import read_trimesh
        from pxr import Gf, Sdf, Usd, UsdGeom, Vt

        textured = texture_of(obj_path) is not None
        # A textured OBJ has one UV per vertex as written: read it back in that order.
        mesh = read_trimesh(obj_path, force="mesh", process=not textured, maintain_order=textured)
        layer = Sdf.Layer.CreateAnonymous(".usda")
        stage = Usd.Stage.Open(layer)
        UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
        UsdGeom.SetStageMetersPerUnit(stage, 1.0)
        prim = UsdGeom.Mesh.Define(stage, "/mesh")
        stage.SetDefaultPrim(prim.GetPrim())
        vertices = np.asarray(mesh.vertices, dtype=np.float32)
        prim.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(vertices))
        prim.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(mesh.faces), 3, dtype=np.int32)))
        prim.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(np.asarray(mesh.faces, dtype=np.int32).reshape(-1)))
        prim.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
        prim.CreateExtentAttr([Gf.Vec3f(*vertices.min(axis=0).tolist()), Gf.Vec3f(*vertices.max(axis=0).tolist())])
        if textured:
            uv = np.asarray(mesh.visual.uv, dtype=np.float32)
            UsdGeom.PrimvarsAPI(prim).CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray,
                                                    UsdGeom.Tokens.vertex).Set(Vt.Vec2fArray.FromNumpy(uv))
        atomic_write(target, layer.ExportToString())
    return target


def _rigid_body(stage, body: Body, folder: Path, references: list[tuple[str, str]]) -> None:
    from pxr import Gf, UsdGeom, UsdPhysics

    obj = body.obj
    path = f"/World/{obj.name}"
    xform = UsdGeom.Xform.Define(stage, path)
    _pose(xform, obj.position, obj.quaternion)
    prim = xform.GetPrim()
    if body.camera is None:
        rigid = UsdPhysics.RigidBodyAPI.Apply(prim)
        if body.fixed:
            rigid.CreateKinematicEnabledAttr(True)
        inertial = body.inertial
        mass = UsdPhysics.MassAPI.Apply(prim)
        mass.CreateMassAttr(inertial.mass)
        mass.CreateCenterOfMassAttr(Gf.Vec3f(*inertial.com))
        mass.CreateDiagonalInertiaAttr(Gf.Vec3f(*inertial.diagonal))
        w, x, y, z = inertial.principal
        mass.CreatePrincipalAxesAttr(Gf.Quatf(w, Gf.Vec3f(x, y, z)))
    for part in body.parts:
        _part_prim(stage, f"{path}/{part.name}", part, folder, obj.color, references)
    if body.camera is not None:
        cam = body.camera
        camera = UsdGeom.Camera.Define(stage, f"{path}/camera")
        _pose(camera, (0.0, 0.0, 0.0), CAMERA_QUAT_NEG_Z)
        focal = CAMERA_VERTICAL_APERTURE / (2 * math.tan(math.radians(cam.fovy) / 2))
        camera.CreateProjectionAttr(UsdGeom.Tokens.perspective)
        camera.CreateFocalLengthAttr(focal)
        camera.CreateVerticalApertureAttr(CAMERA_VERTICAL_APERTURE)
        camera.CreateHorizontalApertureAttr(CAMERA_VERTICAL_APERTURE * cam.width / cam.height)
        camera.CreateClippingRangeAttr(Gf.Vec2f(0.01, 100.0))
        camera.GetPrim().CreateAttribute("prsc:resolution", _int2()).Set(Gf.Vec2i(cam.width, cam.height))


def _int2():
    from pxr import Sdf

    return Sdf.ValueTypeNames.Int2


def _robot_mount(stage, body: Body) -> None:
    """The robot object's Xform at the scene pose and its mount at the box's bottom centre."""
    from pxr import UsdGeom

    obj = body.obj
    xform = UsdGeom.Xform.Define(stage, f"/World/{obj.name}")
    _pose(xform, obj.position, obj.quaternion)
    yaw = body.robot.base_yaw
    mount = UsdGeom.Xform.Define(stage, f"/World/{obj.name}/mount")
    _pose(mount, body.mount_position, (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)))


def _robot_reference(layer, body: Body, asset: Path, folder: Path) -> None:
    """Reference the robot asset under the mount and weld its root joint there.

    Authored with Sdf on the bare layer (no stage open), so the relative asset path is
    not resolved against the in-memory layer.
    """
    from pxr import Gf, Sdf

    path = f"/World/{body.name}/mount/{body.robot.prim_name}"
    spec = Sdf.CreatePrimInLayer(layer, path)
    spec.specifier = Sdf.SpecifierDef
    spec.referenceList.Prepend(Sdf.Reference(relative_path(asset, folder)))
    # The asset's root joint holds the base to the world: its world-side frame is the mount.
    local = np.eye(4)
    local[:3, :3] = rot_z(body.robot.base_yaw)
    local[:3, 3] = body.mount_position
    base = object_matrix(body.obj) @ local
    joint = Sdf.CreatePrimInLayer(layer, f"{path}/joints/root_joint")
    joint.specifier = Sdf.SpecifierOver
    pos = Sdf.AttributeSpec(joint, "physics:localPos0", Sdf.ValueTypeNames.Point3f)
    pos.default = Gf.Vec3f(*(float(v) for v in base[:3, 3]))
    w, x, y, z = matrix_to_quat(base[:3, :3])
    rot = Sdf.AttributeSpec(joint, "physics:localRot0", Sdf.ValueTypeNames.Quatf)
    rot.default = Gf.Quatf(float(w), Gf.Vec3f(float(x), float(y), float(z)))
    if not body.fixed:  # a free-floating robot (`static False`): no weld to the world
        Sdf.AttributeSpec(joint, "physics:jointEnabled", Sdf.ValueTypeNames.Bool).default = False
    _joint_values(layer, path, body)


def _joint_values(layer, path: str, body: Body) -> None:
    """Over the asset (posed at its home): every link where the scene's joint values put it,
    each joint's starting value and each drive's target there (a drawer pulled out, an arm
    in its scene posture)."""
    from pxr import Gf, Sdf

    from prsc.assets.robot_usd import drive_attribute, prim_names, state_attribute, usd_joint_value
    from prsc.geometry.rotations import matrix_to_quat

    robot = body.robot
    values = robot.home(dict(body.obj.joints))
    if values == robot.home():
        return
    tree = robot_tree(robot)
    links, joints = prim_names(tree)
    for name, pose in tree.link_poses(values).items():
        link = Sdf.CreatePrimInLayer(layer, f"{path}/{links[name]}")
        link.specifier = Sdf.SpecifierOver
        Sdf.AttributeSpec(link, "xformOp:translate", Sdf.ValueTypeNames.Double3).default = \
            Gf.Vec3d(*(float(v) for v in pose[:3, 3]))
        w, x, y, z = (float(v) for v in matrix_to_quat(pose[:3, :3]))
        Sdf.AttributeSpec(link, "xformOp:orient", Sdf.ValueTypeNames.Quatd).default = Gf.Quatd(w, Gf.Vec3d(x, y, z))
    for joint in tree.joints:
        if joint.type not in ("revolute", "continuous", "prismatic") or joint.name not in values:
            continue
        spec = Sdf.CreatePrimInLayer(layer, f"{path}/joints/{joints[joint.name]}")
        spec.specifier = Sdf.SpecifierOver
        value = usd_joint_value(joint, values[joint.name])
        Sdf.AttributeSpec(spec, state_attribute(joint), Sdf.ValueTypeNames.Float).default = value
        if not robot.passive:
            Sdf.AttributeSpec(spec, drive_attribute(joint), Sdf.ValueTypeNames.Float).default = value


def _light(stage, body: Body) -> None:
    """A light object: an Xform at its pose holding a UsdLux light turned to shine along the object's
    +y (a UsdLux light shines along its -Z): a DistantLight, or a SphereLight shaped into a cone."""
    from pxr import Gf, UsdGeom, UsdLux

    light = body.light
    assert light is not None
    path = f"/World/{body.obj.name}"
    _pose(UsdGeom.Xform.Define(stage, path), body.obj.position, body.obj.quaternion)
    if light.kind == "directional":
        lux = UsdLux.DistantLight.Define(stage, f"{path}/light")
    else:
        lux = UsdLux.SphereLight.Define(stage, f"{path}/light")
        lux.CreateRadiusAttr(0.01)
        UsdLux.ShapingAPI.Apply(lux.GetPrim()).CreateShapingConeAngleAttr(float(light.cutoff))
    _pose(lux, (0.0, 0.0, 0.0), CAMERA_QUAT_NEG_Z)
    lux.CreateColorAttr(Gf.Vec3f(*light.color))
    lux.CreateIntensityAttr(float(light.intensity))
    UsdLux.ShadowAPI.Apply(lux.GetPrim()).CreateShadowEnableAttr(bool(light.cast_shadow))


def usd_text(scene: Scene, path: Path, store: AssetStore) -> str:
    """The usda text of a scene's stage to be written at `path` (references relative to it)."""
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdPhysics

    folder = Path(path).parent
    bodies = resolve_bodies(scene, store)
    layer = Sdf.Layer.CreateAnonymous(".usda")
    stage = Usd.Stage.Open(layer, Usd.Stage.LoadNone)
    names = {b.name for b in bodies}
    references: list[tuple[str, str]] = []  # (prim, layer relative to the output file)

    def free_name(name: str) -> str:
        while name in names:
            name = "_" + name
        names.add(name)
        return name

    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    UsdPhysics.SetStageKilogramsPerUnit(stage, 1.0)
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    physics = UsdPhysics.Scene.Define(stage, f"/World/{free_name('PhysicsScene')}")
    physics.CreateGravityDirectionAttr(Gf.Vec3f(0.0, 0.0, -1.0))
    physics.CreateGravityMagnitudeAttr(9.81)
    if scene.ground:
        plane = UsdGeom.Plane.Define(stage, f"/World/{free_name('ground')}")
        plane.CreateAxisAttr(UsdGeom.Tokens.z)
        plane.CreateWidthAttr(2 * GROUND_HALF_SIZE)
        plane.CreateLengthAttr(2 * GROUND_HALF_SIZE)
        half = GROUND_HALF_SIZE
        plane.CreateExtentAttr([Gf.Vec3f(-half, -half, 0.0), Gf.Vec3f(half, half, 0.0)])
        _color(plane, (0.8, 0.8, 0.78, 1.0))
        UsdPhysics.CollisionAPI.Apply(plane.GetPrim())
    for body in bodies:
        if body.light is not None:
            _light(stage, body)
        elif body.robot is not None:
            _robot_mount(stage, body)
        else:
            _rigid_body(stage, body, folder, references)
    # References go onto the bare layer after the stage is gone: an open stage would
    # compose them at once against the in-memory layer, which has no folder, and pxr
    # would warn "Could not open asset" for every relative path that is fine on disk.
    del stage
    # Convert robot assets before the change block: building one opens a stage of its own,
    # and no stage can define prims while a change block is open.
    assets = {b.robot: store.robot_usd(b.robot) for b in bodies if b.robot is not None}
    with Sdf.ChangeBlock():
        for prim, asset in references:
            layer.GetPrimAtPath(prim).referenceList.Prepend(Sdf.Reference(asset))
        for body in bodies:
            if body.robot is not None:
                _robot_reference(layer, body, assets[body.robot], folder)
    return layer.ExportToString()


def render(scene: Scene, path: Path, store: AssetStore) -> bytes:
    """Backend entry point: the usda file's bytes."""
    return usd_text(scene, path, store).encode("utf-8")


