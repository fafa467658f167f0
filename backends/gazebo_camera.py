"""The SDF camera `<sensor>` body that the SDF world and the URDF `<gazebo>` extension share."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

from prsc.backends.bodies import CAMERA_QUAT_POS_X
from prsc.backends.numbers import num, nums
from prsc.backends.scene import CameraSpec
from prsc.geometry.rotations import quat_to_rpy

NEAR_CLIP = "0.01"  # metres
FAR_CLIP = "100"


def horizontal_fov(fovy_deg: float, width: int, height: int) -> float:
    """Horizontal field of view (radians) of a pinhole camera with vertical fov `fovy_deg`."""
    return 2 * math.atan(math.tan(math.radians(fovy_deg) / 2) * width / height)


def camera_sensor_body(sensor: ET.Element, cam: CameraSpec) -> None:
    """Fill a `<sensor type="camera">`: its pose on the object link and the camera's intrinsics.

    Gazebo's camera looks along its +X with +Z up; the pose turns that onto the object's +y.
    The caller creates the element, since each format orders its attributes its own way.
    """
    ET.SubElement(sensor, "pose").text = nums((0.0, 0.0, 0.0, *quat_to_rpy(CAMERA_QUAT_POS_X)))
    camera = ET.SubElement(sensor, "camera")
    ET.SubElement(camera, "horizontal_fov").text = num(horizontal_fov(cam.fovy, cam.width, cam.height))
    image = ET.SubElement(camera, "image")
    ET.SubElement(image, "width").text = str(cam.width)
    ET.SubElement(image, "height").text = str(cam.height)
    clip = ET.SubElement(camera, "clip")
    ET.SubElement(clip, "near").text = NEAR_CLIP
    ET.SubElement(clip, "far").text = FAR_CLIP
