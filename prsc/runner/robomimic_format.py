"""robomimic's HDF5 layout with h5py (docs/datasets.md):

    demo.hdf5   data/demo_K  -> an HDF5 external link to demos/demo_K.hdf5:/demo
                data.attrs: total (frames), env_args (JSON); mask/successful (a filter key)
    demos/demo_K.hdf5   /demo: actions (T, A), states (T, S: MuJoCo's integration state),
                        rewards (T,), dones (T,), obs/state, obs/object, obs/<camera>_image
                        (T, H, W, 3 uint8), next_obs/... (the next frame's, the last repeated:
                        robomimic's default config reads them); attrs num_samples, model_file
                        (the MJCF text) and prsc's own (scene JSON, seed, scene index, outcome)

h5py (and robomimic through it, which opens files for SWMR reading: both are written with
libver "latest") reads a linked group as if it were in demo.hdf5. Each
episode's file is written once, whole; demo.hdf5 is small and replaced atomically after
every episode, so a killed recording is a readable file of the episodes before the kill.
"""

from __future__ import annotations

import io
import json

import numpy as np

INDEX_FILE = "demo.hdf5"
DEMO_FILE = "demos/demo_{episode}.hdf5"
DEMO_GROUP = "/demo"


def episode_file(columns: dict[str, np.ndarray], images: dict[str, np.ndarray], names: dict[str, list[str]],
                 attrs: dict[str, object]) -> bytes:
    """One episode's HDF5 file (group /demo) as bytes."""
    import h5py

    buffer = io.BytesIO()
    with h5py.File(buffer, "w", libver="latest") as f:
        demo = f.create_group("demo")

        def put(group, name, values, **kwargs):
            group.create_dataset(name, data=values, track_times=False, **kwargs)

        put(demo, "actions", columns["action"].astype(np.float64))
        put(demo, "states", columns["mujoco.state"])
        put(demo, "rewards", columns["next.reward"].astype(np.float64))
        put(demo, "dones", columns["next.done"].astype(np.int64))
        put(demo, "success", columns["next.success"].astype(np.int64))
        observations = {"state": columns["observation.state"].astype(np.float64),
                        "object": columns["observation.environment_state"],
                        **{f"{camera}_image": frames for camera, frames in images.items()}}
        for group, shift in (("obs", 0), ("next_obs", 1)):
            target = demo.create_group(group)
            for key, values in observations.items():
                values = np.concatenate([values[shift:], values[-1:]]) if shift else values
                if values.dtype == np.uint8:
                    put(target, key, values, compression="gzip", compression_opts=4, chunks=(1, *values.shape[1:]))
                else:
                    put(target, key, values)
        for key, value in names.items():
            demo.attrs[f"{key}_names"] = json.dumps(value)
        demo.attrs["num_samples"] = len(columns["action"])
        for key, value in attrs.items():
            demo.attrs[key] = value
    return buffer.getvalue()


def write_index(path, demos: list[tuple[str, int, bool]], env_args: dict) -> None:
    """demo.hdf5 at `path` (written in place: the caller renames it): data/demo_K linked to each
    episode's file (file, frames, success), and the filter key mask/successful (robomimic's
    `hdf5_filter_key`) naming the demos whose task succeeded."""
    import h5py

    # locking=False: the temporary is already locked by prsc.files.atomic_path, whose lock HDF5 would meet
    with h5py.File(path, "w", libver="latest", locking=False) as f:
        data = f.create_group("data")
        for k, (file, _, _) in enumerate(demos):
            data[f"demo_{k}"] = h5py.ExternalLink(file, DEMO_GROUP)
        data.attrs["total"] = int(sum(n for _, n, _ in demos))
        data.attrs["env_args"] = json.dumps(env_args)
        names = [f"demo_{k}" for k, (_, _, success) in enumerate(demos) if success]
        f.create_dataset("mask/successful", data=np.array(names, dtype="S"), shape=(len(names),), dtype="S16")
