"""Textured meshes as users bring them (docs/backends.md, "Textured meshes"): pybullet's
duck (OBJ + MTL + PNG, modelled y-up) and the same duck as a GLB keep their UVs and
base-colour image in every format, stand upright with `upAxis "+y"`, and a missing image
is an error `prsc check` reports at the line that names the mesh."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.backends import readback

pybullet_data = pytest.importorskip("pybullet_data")
DATA = Path(pybullet_data.getDataPath())
DUCK_SCALE = 0.1  # duck.obj is 1.65 x 1.54 x 1.15 units (x, y-up, z)

SPEC = """\
from tabletop import *

class Duck:
    mesh: "duck.obj"
    upAxis: "+y"
    scale: 0.1

class GlbDuck:
    mesh: "duck.glb"
    upAxis: "+y"
    scale: 0.1

t = Table on Vector3D(0, 0, 0), with width 1.2, with length 0.8, with height 0.75
d = Duck completely on t
g = GlbDuck completely on t
"""


def _prsc(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "prsc.cli", *args], capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def compiled(tmp_path_factory) -> Path:
    """The duck spec compiled to every format, then moved: the output folder as a user copies it."""
    import trimesh

    folder = tmp_path_factory.mktemp("ducks")
    trimesh.load(DATA / "duck.obj", force="mesh").export(folder / "duck.glb")
    (folder / "ducks.prs").write_text(SPEC)
    done = _prsc("compile", str(folder / "ducks.prs"), "-I", str(DATA), "-n", "2",
                 "--target", "json,mjcf,urdf,sdf,usd", "-o", str(folder / "out"))
    assert done.returncode == 0, done.stdout + done.stderr
    moved = folder / "moved"
    shutil.move(folder / "out", moved)
    return moved / "ducks"


def _model(root: Path):
    import mujoco

    return mujoco.MjModel.from_xml_path(str(root / "mjcf" / "00000.xml"))


def test_mjcf_has_the_texture_and_the_mesh_its_uvs(compiled):
    import mujoco

    model = _model(compiled)
    for name in ("d/mesh", "g/mesh"):
        mesh = model.mesh(name).id
        assert model.mesh_texcoordnum[mesh] == model.mesh_vertnum[mesh] > 0
        geom = model.geom(name)
        material = int(geom.matid[0])
        texture = model.mat_texid[material, mujoco.mjtTextureRole.mjTEXROLE_RGB]
        assert texture >= 0 and model.tex_width[texture] == 512  # duckCM.png is 512 x 512
    assert model.ntex >= 3  # the floor's checker and one per duck


def _duck_pixels(model, data, textured: bool) -> np.ndarray:
    """The RGB pixels of duck `d` seen from the front, with its texture on or off."""
    return _geom_pixels(model if textured else _untextured(model), data, "d/mesh", 0.35, 0.0, -15.0)


def _geom_pixels(model, data, geom: str, distance: float = 0.4, azimuth: float = 90.0, elevation: float = -20.0) -> np.ndarray:
    """The RGB pixels of one geom, seen from `distance` at `azimuth` and `elevation` (degrees)."""
    import mujoco

    renderer = mujoco.Renderer(model, 240, 320)
    camera = mujoco.MjvCamera()
    camera.lookat[:] = data.geom_xpos[model.geom(geom).id]
    camera.distance, camera.azimuth, camera.elevation = distance, azimuth, elevation
    renderer.update_scene(data, camera)
    image = renderer.render().copy()
    renderer.enable_segmentation_rendering()
    renderer.update_scene(data, camera)
    ids = renderer.render()[..., 0]
    renderer.close()
    return image[ids == model.geom(geom).id].astype(float)


def _untextured(model):
    import copy

    import mujoco

    plain = copy.copy(model)
    plain.mat_texid[:, mujoco.mjtTextureRole.mjTEXROLE_RGB] = -1
    return plain


def test_a_render_shows_the_texture(compiled):
    import mujoco

    model = _model(compiled)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    textured = _duck_pixels(model, data, True)
    plain = _duck_pixels(model, data, False)
    assert len(textured) > 2000  # the duck fills a good part of the view
    # A white untextured duck is white and grey; the textured one is yellow (blue well below red).
    assert np.mean(plain[:, 0] - plain[:, 2]) < 5
    assert np.mean(textured[:, 0] - textured[:, 2]) > 60
    # Not a single colour: the image's yellows and oranges give far more colour bins than shading alone.
    bins = [len({tuple(p) for p in (pixels // 32).astype(int)}) for pixels in (textured, plain)]
    assert bins[0] >= 2 * bins[1], bins  # measured: 50 against 16


def test_the_y_up_duck_stands_upright_and_rests(compiled):
    import mujoco

    scene = json.loads((compiled / "json" / "00000.json").read_text())
    duck = next(o for o in scene["objects"] if o["name"] == "d")
    low, high = np.array([-0.961799, 0.099294, -0.539252]), np.array([0.692985, 1.6397, 0.613282])
    extent = (high - low) * DUCK_SCALE
    np.testing.assert_allclose(duck["dimensions"], [extent[0], extent[2], extent[1]], rtol=1e-6)
    model = _model(compiled)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    start = data.xpos[model.body("d").id].copy()
    while data.time < 1.0:
        mujoco.mj_step(model, data)
    assert np.linalg.norm(data.xpos[model.body("d").id] - start) < 0.002


def test_usd_has_uvs_and_a_preview_surface_whose_image_resolves_after_a_move(compiled):
    from pxr import Usd, UsdGeom, UsdShade

    path = compiled / "usd" / "00000.usda"
    assert readback.usd_errors(path) == []
    stage = Usd.Stage.Open(str(path))
    for name in ("d", "g"):
        prim = stage.GetPrimAtPath(f"/World/{name}/mesh")
        st = UsdGeom.PrimvarsAPI(prim).GetPrimvar("st")
        assert st and len(st.Get()) == len(UsdGeom.Mesh(prim).GetPointsAttr().Get())
        material, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
        surface = material.ComputeSurfaceSource()[0]
        assert surface.GetIdAttr().Get() == "UsdPreviewSurface"
        image = surface.GetInput("diffuseColor").GetConnectedSources()[0][0].source
        shader = UsdShade.Shader(image.GetPrim())
        assert shader.GetIdAttr().Get() == "UsdUVTexture"
        resolved = shader.GetInput("file").Get().resolvedPath
        assert resolved and Path(resolved).is_file() and Path(resolved).is_relative_to(compiled)


def test_urdf_and_sdf_carry_the_mesh_with_its_material_and_image(compiled):
    import xml.etree.ElementTree as ET

    import pybullet as p

    bundle = compiled / "urdf" / "00000"
    client = p.connect(p.DIRECT)
    try:
        body = p.loadURDF(str(bundle / "d.urdf"), physicsClientId=client)
        shapes = p.getVisualShapeData(body, flags=p.VISUAL_SHAPE_DATA_TEXTURE_UNIQUE_IDS, physicsClientId=client)
        assert shapes[0][7] == (1.0, 1.0, 1.0, 1.0)  # white: the image is not tinted
        assert shapes[0][8] >= 0  # pybullet loaded a texture for it
    finally:
        p.disconnect(client)
    sdf = ET.parse(compiled / "sdf" / "00000.sdf")
    visual = next(v for v in sdf.iter("visual") if v.get("name") == "mesh_visual"
                  and v.find("geometry/mesh/uri").text.endswith(".obj"))
    assert visual.find("material") is None  # the OBJ's MTL colours it
    obj = (compiled / "sdf" / visual.find("geometry/mesh/uri").text).resolve()
    assert f"mtllib {obj.stem}.mtl" in obj.read_text()
    assert f"map_Kd {obj.stem}.png" in obj.with_suffix(".mtl").read_text()
    assert obj.with_suffix(".png").is_file()


@pytest.mark.parametrize("case", ["missing image", "bad upAxis"])
def test_check_reports_a_missing_image_and_a_bad_up_axis_at_the_line(tmp_path, case):
    shutil.copy(DATA / "duck.obj", tmp_path / "duck.obj")
    shutil.copy(DATA / "duck.mtl", tmp_path / "duck.mtl")  # names duckCM.png, which is not copied
    up = '"+y"' if case == "missing image" else '"up"'
    if case == "bad upAxis":
        shutil.copy(DATA / "duckCM.png", tmp_path / "duckCM.png")
    (tmp_path / "spec.prs").write_text(f'from tabletop import *\nt = Table on Vector3D(0, 0, 0)\n'
                                       f'd = Object completely on t, with mesh "duck.obj", with upAxis {up}\n')
    for command in ("check", "compile"):
        done = _prsc(command, str(tmp_path / "spec.prs"), *(["-o", str(tmp_path / "out")] if command == "compile" else []))
        assert done.returncode == 2, done.stdout + done.stderr
        assert "Traceback" not in done.stderr
        if case == "missing image":
            assert "spec.prs:3:39" in done.stderr and "duckCM.png" in done.stderr, done.stderr
        else:
            assert "spec.prs:3:" in done.stderr and "upAxis is 'up'" in done.stderr, done.stderr
    assert not (tmp_path / "out").exists()


def test_preview_finds_the_mesh_in_the_include_folder_and_shows_its_texture(tmp_path):
    from PIL import Image

    (tmp_path / "duck.prs").write_text('from tabletop import *\nt = Table on Vector3D(0, 0, 0), with width 0.5, '
                                       'with length 0.5, with height 0.75\n'
                                       'd = Object completely on t, with mesh "duck.obj", with upAxis "+y", '
                                       'with scale 0.15\n')
    done = _prsc("preview", str(tmp_path / "duck.prs"), "-I", str(DATA), "-n", "1", "-o", str(tmp_path / "sheet.png"))
    assert done.returncode == 0, done.stdout + done.stderr
    pixels = np.asarray(Image.open(tmp_path / "sheet.png").convert("RGB")).reshape(-1, 3).astype(int)
    yellow = (pixels[:, 0] > 150) & (pixels[:, 1] > 120) & (pixels[:, 2] < 60)  # the duck's texture, nothing else
    assert yellow.sum() > 500, yellow.sum()


def _image(path: Path, colour: tuple[int, int, int]) -> Path:
    """A 32 x 32 PNG of one colour with a white stripe (so it is an image, not a colour)."""
    from PIL import Image

    pixels = np.zeros((32, 32, 3), np.uint8)
    pixels[:] = colour
    pixels[:, :4] = 255
    Image.fromarray(pixels).save(path)
    return path


def test_with_texture_puts_an_image_on_a_box_in_every_format(tmp_path):
    import mujoco
    from pxr import Usd, UsdGeom, UsdShade

    _image(tmp_path / "red.png", (200, 0, 0))
    _image(tmp_path / "green.png", (0, 200, 0))
    (tmp_path / "crates.prs").write_text(
        'from tabletop import *\nt = Table on Vector3D(0, 0, 0), with width 1.2, with length 0.8, with height 0.75\n'
        'crate = Cube completely on t, with texture Options(["red.png", "green.png"])\n')
    done = _prsc("compile", str(tmp_path / "crates.prs"), "-n", "6", "--target", "json,mjcf,urdf,sdf,usd",
                 "-o", str(tmp_path / "out"))
    assert done.returncode == 0, done.stdout + done.stderr
    root = tmp_path / "out" / "crates"
    drawn = set()
    for k in range(6):
        scene = json.loads((root / "json" / f"{k:05d}.json").read_text())
        chosen = next(o for o in scene["objects"] if o["name"] == "crate")["properties"]["texture"]
        drawn.add(chosen)
        model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / f"{k:05d}.xml"))
        material = int(model.geom("crate/box").matid[0])
        texture = model.mat_texid[material, mujoco.mjtTextureRole.mjTEXROLE_RGB]
        assert model.tex_type[texture] == mujoco.mjtTexture.mjTEXTURE_CUBE
        texels = model.tex_data[model.tex_adr[texture]:model.tex_adr[texture] + 32 * 32 * 3].reshape(-1, 3)
        assert (texels == 255).all(axis=1).sum() == 32 * 4  # the image's white stripe
        channel = {"red.png": 0, "green.png": 1}[chosen]
        assert int(np.median(texels[:, channel])) == 200
        stage = Usd.Stage.Open(str(root / "usd" / f"{k:05d}.usda"))
        prim = stage.GetPrimAtPath("/World/crate/box")
        assert prim.IsA(UsdGeom.Mesh) and UsdGeom.PrimvarsAPI(prim).GetPrimvar("st")
        material, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
        image = material.ComputeSurfaceSource()[0].GetInput("diffuseColor").GetConnectedSources()[0][0].source
        assert Path(UsdShade.Shader(image.GetPrim()).GetInput("file").Get().resolvedPath).name.startswith(chosen[:-4])
        assert readback.usd_errors(root / "usd" / f"{k:05d}.usda") == []
        assert f"textures/{chosen[:-4]}-" in (root / "sdf" / f"{k:05d}.sdf").read_text()  # the albedo map
        assert f"textures/{chosen[:-4]}-" in (root / "urdf" / f"{k:05d}" / "crate.urdf").read_text()
    assert drawn == {"red.png", "green.png"}  # drawn per scene


def test_with_texture_wraps_an_image_round_a_cylinder_and_a_sphere(tmp_path):
    import mujoco
    from pxr import Usd, UsdGeom, UsdShade

    _image(tmp_path / "red.png", (200, 0, 0))
    (tmp_path / "round.prs").write_text(
        'from tabletop import *\nt = Table on Vector3D(0, 0, 0), with width 1.2, with length 0.8, with height 0.75\n'
        'can = Cylinder completely on t, with width 0.08, with length 0.08, with height 0.12, with texture "red.png"\n'
        'ball = Object completely on t, with shape "sphere", with width 0.1, with length 0.1, with height 0.1, '
        'with texture "red.png"\n')
    done = _prsc("compile", str(tmp_path / "round.prs"), "-n", "1", "--target", "json,mjcf,urdf,sdf,usd",
                 "-o", str(tmp_path / "out"))
    assert done.returncode == 0, done.stdout + done.stderr
    root = tmp_path / "out" / "round"
    model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / "00000.xml"))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    stage = Usd.Stage.Open(str(root / "usd" / "00000.usda"))
    assert readback.usd_errors(root / "usd" / "00000.usda") == []
    for geom, shape in (("can/cylinder", "cylinder"), ("ball/sphere", "sphere")):
        assert model.geom(geom).type[0] == getattr(mujoco.mjtGeom, f"mjGEOM_{shape.upper()}")  # it still collides as itself
        texture = model.mat_texid[int(model.geom(geom).matid[0]), mujoco.mjtTextureRole.mjTEXROLE_RGB]
        assert model.tex_type[texture] == mujoco.mjtTexture.mjTEXTURE_CUBE
        # Drawn: red with the image's white stripe (a white untextured geom shows no red at all).
        pixels = _geom_pixels(model, data, geom)
        assert len(pixels) > 1000 and np.mean(pixels[:, 0] - pixels[:, 1]) > 60
        assert ((pixels.min(axis=1) > 150).sum()) > 20, geom
        # USD: a mesh with one texture coordinate per face corner, bound to the image.
        prim = stage.GetPrimAtPath(f"/World/{geom}")
        assert prim.IsA(UsdGeom.Mesh), geom
        mesh = UsdGeom.Mesh(prim)
        st = UsdGeom.PrimvarsAPI(prim).GetPrimvar("st").Get()
        assert len(st) == len(mesh.GetFaceVertexIndicesAttr().Get()) == sum(mesh.GetFaceVertexCountsAttr().Get())
        points = np.array(mesh.GetPointsAttr().Get())
        radius = np.linalg.norm(points[:, :2], axis=1) if shape == "cylinder" else np.linalg.norm(points, axis=1)
        assert np.allclose(radius[radius > 0.25], 0.5, atol=1e-6) and np.abs(points).max() <= 0.5 + 1e-6
        material, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
        image = material.ComputeSurfaceSource()[0].GetInput("diffuseColor").GetConnectedSources()[0][0].source
        assert Path(UsdShade.Shader(image.GetPrim()).GetInput("file").Get().resolvedPath).name.startswith("red-")
        assert "textures/red-" in (root / "urdf" / "00000" / f"{geom.split('/')[0]}.urdf").read_text()
    assert (root / "sdf" / "00000.sdf").read_text().count("textures/red-") == 2


@pytest.mark.parametrize("line, message", [
    ('c = Object on t, with shape "mesh", with texture "red.png"', "none of them"),
    ('c = Cube on t, with texture "blue.png"', "not found"),
    ('c = Cube on t, with texture "notes.png"', "cannot read image"),
])
def test_check_reports_a_bad_texture_at_its_line(tmp_path, line, message):
    _image(tmp_path / "red.png", (200, 0, 0))
    (tmp_path / "notes.png").write_text("not an image")
    (tmp_path / "spec.prs").write_text(f"from tabletop import *\nt = Table on Vector3D(0, 0, 0)\n{line}\n")
    done = _prsc("check", str(tmp_path / "spec.prs"))
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert "spec.prs:3:" in done.stderr and message in done.stderr, done.stderr


PBR_SPEC = """\
from tabletop import *

class Tile:
    mesh: "tile.glb"
    width: 0.1
    length: 0.1
    height: 0.05

t = Table on Vector3D(0, 0, 0), with width 1.2, with length 0.8, with height 0.75
tile = Tile completely on t
"""


def test_a_glb_keeps_its_normal_and_roughness_metallic_maps(tmp_path):
    """A glTF mesh with a normal map and glTF's metallic-roughness image (made here with
    trimesh): MJCF's material reads them as its `normal` and `orm` layers (linear), USD's
    UsdPreviewSurface as `normal` (scaled to [-1, 1]) and `roughness`/`metallic` (G and B),
    and the store's MTL, which URDF and SDF meshes carry, names them; their pixels arrive."""
    import mujoco
    import trimesh
    from PIL import Image
    from pxr import Usd, UsdShade

    box = trimesh.creation.box(extents=[1.0, 1.0, 0.5])
    box.unmerge_vertices()
    rng = np.random.default_rng(0)
    images = {"base": Image.fromarray((rng.random((16, 16, 3)) * 255).astype(np.uint8)),
              "normal": Image.fromarray(np.full((16, 16, 3), [128, 128, 255], np.uint8)),
              "orm": Image.fromarray(np.full((16, 16, 3), [255, 200, 30], np.uint8))}
    material = trimesh.visual.material.PBRMaterial(baseColorTexture=images["base"], normalTexture=images["normal"],
                                                   metallicRoughnessTexture=images["orm"])
    box.visual = trimesh.visual.TextureVisuals(uv=rng.random((len(box.vertices), 2)), material=material)
    box.export(tmp_path / "tile.glb")
    (tmp_path / "pbr.prs").write_text(PBR_SPEC)
    done = _prsc("compile", str(tmp_path / "pbr.prs"), "-n", "1", "--target", "json,mjcf,urdf,usd",
                 "-o", str(tmp_path / "out"))
    assert done.returncode == 0, done.stdout + done.stderr
    root = tmp_path / "out" / "pbr"

    model = _model(root)
    matid = int(model.geom("tile/mesh").matid[0])
    for role, colour in ((mujoco.mjtTextureRole.mjTEXROLE_NORMAL, [128, 128, 255]),
                         (mujoco.mjtTextureRole.mjTEXROLE_ORM, [255, 200, 30])):
        tex = model.mat_texid[matid, role]
        assert tex >= 0
        assert model.tex_colorspace[tex] == mujoco.mjtColorSpace.mjCOLORSPACE_LINEAR
        start, size = model.tex_adr[tex], model.tex_width[tex] * model.tex_height[tex] * model.tex_nchannel[tex]
        pixels = model.tex_data[start:start + size].reshape(-1, model.tex_nchannel[tex])[:, :3]
        assert (pixels == colour).all()

    usda = root / "usd" / "00000.usda"
    assert readback.usd_errors(usda) == []
    stage = Usd.Stage.Open(str(usda))
    surface = next(UsdShade.Shader(p) for p in stage.Traverse()
                   if p.IsA(UsdShade.Shader) and UsdShade.Shader(p).GetIdAttr().Get() == "UsdPreviewSurface")
    sources = {}
    for name in ("normal", "roughness", "metallic"):
        (info,) = surface.GetInput(name).GetConnectedSources()[0]
        sources[name] = (UsdShade.Shader(info.source.GetPrim()), info.sourceName)
    assert sources["roughness"][1] == "g" and sources["metallic"][1] == "b"
    normal, _ = sources["normal"]
    assert tuple(normal.GetInput("scale").Get()) == (2.0, 2.0, 2.0, 1.0)
    assert normal.GetInput("sourceColorSpace").Get() == "raw"
    for shader, _ in sources.values():
        image = (usda.parent / shader.GetInput("file").Get().path).resolve()
        assert image.is_file()
    assert np.array_equal(np.asarray(Image.open(usda.parent / normal.GetInput("file").Get().path))[..., :3],
                          np.asarray(images["normal"]))

    mtl = next((root / "assets" / "meshes").glob("tile-*.mtl")).read_text()
    assert "norm tile-" in mtl and "map_Pr -imfchan g" in mtl and "map_Pm -imfchan b" in mtl
