"""What a demonstration dataset records of an episode, frame by frame: the robots' joints and
grippers, the controls sent, the scene's objects, the spec's cameras, the MuJoCo state and the
task's reward (docs/datasets.md).

`DemoLayout` names the recorded quantities of one model once; `DemoRecorder` is the
PeriodicCallback (prsc/runner/step_hook.py) that takes a frame every 1/fps simulated seconds
from inside `mj_step`, where positions, contacts and `data.ctrl` (what the controller set for
that step) are consistent, whatever the controller does.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import mujoco
import numpy as np

from prsc.backends.names import with_body_names

from prsc.runner.step_hook import PeriodicCallback

STATE_SPEC = mujoco.mjtState.mjSTATE_INTEGRATION  # everything mj_step reads: time, qpos, qvel, act, warmstart, ctrl, ...
_SLIDE_OR_HINGE = (int(mujoco.mjtJoint.mjJNT_SLIDE), int(mujoco.mjtJoint.mjJNT_HINGE))


@dataclass(frozen=True)
class Camera:
    """A camera object of the scene: its name in the model and its image size."""

    name: str
    camera_id: int
    width: int
    height: int


@dataclass(frozen=True)
class RobotGripper:
    """A robot's finger bodies and the tool frame and axis their spread is measured along."""

    fingers: tuple[int, ...]  # body ids
    tool: int
    tool_is_site: bool
    closing: np.ndarray  # in the tool's frame


@dataclass(frozen=True)
class DemoLayout:
    """Which numbers of a model each recorded feature holds, and their names."""

    state_qpos: np.ndarray  # qpos address per robot joint
    grippers: tuple[RobotGripper, ...]
    state_names: tuple[str, ...]  # joints then each gripper's opening
    actuators: np.ndarray  # actuator ids, robots' in model order
    action_names: tuple[str, ...]
    object_bodies: np.ndarray  # body id per free scene object
    object_names: tuple[str, ...]  # 7 per object: x y z qw qx qy qz
    cameras: tuple[Camera, ...]
    state_size: int  # of the MuJoCo state (STATE_SPEC)

    @staticmethod
    def of(scene: dict, model: mujoco.MjModel) -> DemoLayout:
        """The layout of a scene's compiled model: robots are objects with hinge or slide joints
        named after them, cameras the objects with camera properties."""
        objects = with_body_names(scene)["objects"]
        joint_names = [model.joint(j).name for j in range(model.njnt)]
        qpos, names, grippers, actuators, action_names = [], [], [], [], []
        bodies, object_names, cameras = [], [], []
        for obj in objects:
            body = obj["body"]
            prefix = body + "/"
            joints = [j for j, n in enumerate(joint_names) if n.startswith(prefix) and int(model.jnt_type[j]) in _SLIDE_OR_HINGE]
            if obj.get("camera") is not None:
                resolution = obj["camera"].get("resolution", [640, 480])
                cameras.append(Camera(body, mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, body),
                                      int(resolution[0]), int(resolution[1])))
            elif joints:
                qpos += [int(model.jnt_qposadr[j]) for j in joints]
                names += [joint_names[j] for j in joints]
                gripper = _gripper(obj, model)
                if gripper is not None:
                    grippers.append(gripper)
                    names.append(f"{prefix}gripper_opening")
                for a in range(model.nu):
                    if model.actuator(a).name.startswith(prefix):
                        actuators.append(a)
                        action_names.append(model.actuator(a).name)
            else:
                found = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body)
                if found >= 0 and any(int(model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE)
                                      for j in range(model.body_jntadr[found], model.body_jntadr[found] + model.body_jntnum[found])):
                    bodies.append(found)
                    object_names += [f"{body}.{axis}" for axis in ("x", "y", "z", "qw", "qx", "qy", "qz")]
        return DemoLayout(np.array(qpos, dtype=int), tuple(grippers), tuple(names), np.array(actuators, dtype=int),
                          tuple(action_names), np.array(bodies, dtype=int), tuple(object_names), tuple(cameras),
                          mujoco.mj_stateSize(model, STATE_SPEC))

    def state(self, data: mujoco.MjData) -> np.ndarray:
        """The robots' joint positions and gripper openings (metres between the finger bodies' centres
        of mass along the gripper's closing axis)."""
        return np.concatenate([data.qpos[self.state_qpos], [_opening(g, data) for g in self.grippers]])

    def action(self, data: mujoco.MjData) -> np.ndarray:
        """The robots' actuator controls as the controller set them."""
        return data.ctrl[self.actuators].copy()

    def objects(self, data: mujoco.MjData) -> np.ndarray:
        """Each free scene object's position and orientation quaternion (world frame)."""
        return np.concatenate([data.xpos[self.object_bodies], data.xquat[self.object_bodies]], axis=1).reshape(-1)


def _gripper(obj: dict, model: mujoco.MjModel) -> RobotGripper | None:
    """The robot object's gripper as the shipped controllers find it (prsc/runner/gripper.py), or None."""
    from prsc.runner.arm_scene import chain_joints, driven_joints
    from prsc.runner.gripper import gripper_of
    from prsc.assets.articulated import robot_model
    from prsc.user_assets.arm_ik import ArmFrames

    try:
        asset = robot_model(obj.get("model"))
    except Exception:  # noqa: BLE001 - not an asset prsc knows as a robot: no gripper to measure
        return None
    if asset is None:
        return None
    prefix = obj["body"] + "/"
    tool = prefix + str((obj.get("properties") or {}).get("tcp") or asset.tcp)
    try:
        moving = chain_joints(model, tool) & driven_joints(model)
    except KeyError:
        return None
    joints = [prefix + j.name for j in asset.joints if prefix + j.name in moving]
    if not joints:
        return None
    frames = ArmFrames.of(model, joints, tool)
    gripper = gripper_of(model, prefix, frames, tool)
    if gripper is None:
        return None
    fingers = []
    for a in gripper.actuators:
        if int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT):
            fingers.append(int(model.jnt_bodyid[model.actuator_trnid[a, 0]]))
    # a tendon-driven gripper: the bodies of the other joints under the prefix off the arm's chain
    chain = chain_joints(model, tool)
    fingers += [int(model.jnt_bodyid[j]) for j in range(model.njnt) if model.joint(j).name.startswith(prefix)
                and model.joint(j).name not in chain and int(model.jnt_type[j]) in _SLIDE_OR_HINGE]
    return RobotGripper(tuple(sorted(set(fingers))), frames.tool, frames.tool_is_site, gripper.closing)


def _opening(gripper: RobotGripper, data: mujoco.MjData) -> float:
    if gripper.tool_is_site:
        position, rotation = data.site_xpos[gripper.tool], data.site_xmat[gripper.tool].reshape(3, 3)
    else:
        position, rotation = data.xpos[gripper.tool], data.xmat[gripper.tool].reshape(3, 3)
    along = [(rotation.T @ (data.xipos[b] - position)) @ gripper.closing for b in gripper.fingers]
    return float(max(along) - min(along)) if len(along) > 1 else float(2.0 * abs(along[0]))


def task_values(status: Any, last: bool) -> tuple[float, bool, bool]:
    """(next.reward, next.done, next.success) of a frame from the task's status at it (a TaskStatus
    with `outcome` None while undecided, "success", "fail:LABEL" or "timeout"), or None without a
    task: reward 1 from the frame the task succeeded, done from the frame it was decided (and on
    the episode's last frame), success once it succeeded."""
    outcome = None if status is None else getattr(status, "outcome", None)
    success = outcome == "success"
    return (1.0 if success else 0.0), bool(last or outcome is not None), success


@dataclass
class EpisodeFrames:
    """The frames of one episode, as recorded (arrays stacked by `frames`)."""

    layout: DemoLayout
    fps: float
    times: list[float] = field(default_factory=list)
    states: list[np.ndarray] = field(default_factory=list)
    actions: list[np.ndarray] = field(default_factory=list)
    objects: list[np.ndarray] = field(default_factory=list)
    mujoco_states: list[np.ndarray] = field(default_factory=list)
    statuses: list[Any] = field(default_factory=list)
    images: dict[str, list[np.ndarray]] = field(default_factory=dict)
    values: list[tuple[float, bool, bool]] | None = None  # (reward, done, success) given per frame, not from statuses

    def __len__(self) -> int:
        return len(self.times)

    def columns(self) -> dict[str, np.ndarray]:
        """The per-frame arrays, named as the LeRobot features (images apart)."""
        n = len(self)
        values = self.values if self.values is not None else [task_values(s, k == n - 1) for k, s in enumerate(self.statuses)]
        layout = self.layout
        return {
            "observation.state": np.array(self.states, dtype=np.float32).reshape(n, len(layout.state_names)),
            "action": np.array(self.actions, dtype=np.float32).reshape(n, len(layout.action_names)),
            "observation.environment_state": np.array(self.objects, dtype=np.float64).reshape(n, len(layout.object_names)),
            "mujoco.state": np.array(self.mujoco_states, dtype=np.float64).reshape(n, layout.state_size),
            "next.reward": np.array([v[0] for v in values], dtype=np.float32),
            "next.done": np.array([v[1] for v in values], dtype=bool),
            "next.success": np.array([v[2] for v in values], dtype=bool),
        }

    def image_stack(self, camera: str) -> np.ndarray:
        """The camera's frames, (T, H, W, 3) uint8."""
        cam = next(c for c in self.layout.cameras if c.name == camera)
        return np.array(self.images[camera], dtype=np.uint8).reshape(len(self), cam.height, cam.width, 3)


class DemoRecorder:
    """Records frames of one episode; `periodic` is its PeriodicCallback for the harness's StepHook.

    `task_status()` (optional) returns the task monitor's latest status at the frame."""

    def __init__(self, scene: dict, fps: float, task_status: Callable[[], Any] | None = None, images: bool = True):
        self.scene = scene
        self.fps = fps
        self.task_status = task_status
        self.images = images
        self.frames: EpisodeFrames | None = None
        self._renderers: dict[tuple[int, int], Any] = {}

    @property
    def periodic(self) -> PeriodicCallback:
        """A frame every 1/fps simulated seconds, the first at the episode's start."""
        return PeriodicCallback(1.0 / self.fps, self.capture)

    def capture(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Take one frame of (model, data): every part first, then appended together."""
        if self.frames is None:
            layout = DemoLayout.of(self.scene, model)
            self.frames = EpisodeFrames(layout, self.fps, images={c.name: [] for c in layout.cameras})
        frames = self.frames
        layout = frames.layout
        images = {c.name: self._render(model, data, c) for c in layout.cameras} if self.images else {}
        state = np.empty(layout.state_size)
        mujoco.mj_getState(model, data, state, STATE_SPEC)
        status = self.task_status() if self.task_status is not None else None
        frames.times.append(float(data.time))
        frames.states.append(layout.state(data))
        frames.actions.append(layout.action(data))
        frames.objects.append(layout.objects(data))
        frames.mujoco_states.append(state)
        frames.statuses.append(status)
        for name, image in images.items():
            frames.images[name].append(image)

    def _render(self, model: mujoco.MjModel, data: mujoco.MjData, camera: Camera) -> np.ndarray:
        from prsc.runner.rendering import OffscreenRenderer

        key = (camera.width, camera.height)
        if key not in self._renderers:
            self._renderers[key] = OffscreenRenderer(model, camera.width, camera.height)
        return self._renderers[key].rgb(data, camera.camera_id)

    def close(self) -> None:
        """Release the render contexts."""
        for renderer in self._renderers.values():
            renderer.close()
        self._renderers = {}
