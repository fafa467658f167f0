"""Node loss on Ray (docs/ray.md, "Measured"): 40 Table-Cube episodes (default handover
controller), local `--jobs 2` and then on a 3-node local Ray cluster (head without CPUs, two
1-CPU workers) started without MUJOCO_GL, one worker node killed once 10 episodes are
recorded; prints both wall times and whether every record equals the local run's.

    .venv/bin/python bench/ray_node_loss.py   # about 5 min of CPU; writes /tmp/prsc_ray_node_loss
"""
import json, os, shutil, subprocess, sys, time
from pathlib import Path
for k in ("MUJOCO_GL", "PYOPENGL_PLATFORM"):
    os.environ.pop(k, None)
REPO = str(Path(__file__).resolve().parents[1])
PY = sys.executable
OUT = "/tmp/prsc_ray_node_loss"
shutil.rmtree(OUT, ignore_errors=True); os.makedirs(OUT)
common = [PY, "-m", "prsc.cli", "run", REPO + "/specs/table_cube.prs", "-n", "40", "--seed", "0"]

def records(path):
    return [{k: v for k, v in json.loads(l).items() if k != "wall_seconds"} for l in open(path)]

t = time.time()
local = subprocess.run(common + ["--jobs", "2", "-o", OUT + "/local"], capture_output=True, text=True, cwd=REPO)
local_s = time.time() - t
print("local rc", local.returncode, f"{local_s:.1f} s", local.stderr.strip().splitlines()[-2:], flush=True)

from ray.cluster_utils import Cluster
cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 0, "object_store_memory": 200 * 2**20})
nodes = [cluster.add_node(num_cpus=1, object_store_memory=200 * 2**20) for _ in range(2)]
t = time.time()
run = subprocess.Popen(common + ["--executor", "ray", "--address", cluster.address, "-o", OUT + "/ray"],
                       stderr=subprocess.PIPE, text=True, cwd=REPO)
res = OUT + "/ray/results.jsonl"
while run.poll() is None and not (os.path.exists(res) and open(res).read().count("\n") >= 10):
    time.sleep(0.2)
at_kill = open(res).read().count("\n") if os.path.exists(res) else 0
killed_at = time.time() - t
cluster.remove_node(nodes[0], allow_graceful=False)
err = run.stderr.read(); rc = run.wait()
ray_s = time.time() - t
print("ray rc", rc, f"{ray_s:.1f} s", f"node killed at {killed_at:.1f} s with {at_kill} episodes recorded", flush=True)
print("\n".join(l for l in err.splitlines() if "prsc" in l or "compile" in l or "CPUs" in l)[-1500:])
a, b = records(OUT + "/local/results.jsonl"), records(res)
idx = [r["index"] for r in b]
print("indices distinct", len(set(idx)), "in order", idx == list(range(40)), "outcomes equal", a == b)
from collections import Counter
print("outcomes", Counter(r["outcome"] for r in b))
cluster.shutdown()
