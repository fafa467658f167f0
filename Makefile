# prsc build: every target sets up .venv itself when it is missing.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
PRSC := $(VENV)/bin/prsc
STAMP := $(VENV)/.installed
export MUJOCO_GL ?= egl
export PYOPENGL_PLATFORM ?= egl

.PHONY: setup test test-slow test-cluster demo docs datasets bench casestudy casestudy-check clean lerobot-check

setup: $(STAMP)

# --no-compile: pip byte-compiles every module it installs (23 of 53 s of a fresh install
# here); Python compiles the ones a command imports on first use instead (about 5 s).
$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q --no-compile -e '.[dev,ray,gym,datasets]'
	touch $(STAMP)

test: $(STAMP)
	$(PY) -m pytest -q -n 2 --dist loadfile -m "not cluster and not slow"

# The slowest tests (tests/conftest.py, SLOW): kept out of `make test`'s 4 minutes; CI runs them.
test-slow: $(STAMP)
	$(PY) -m pytest -q -n 2 --dist loadfile -m slow

# A local multi-node Ray cluster losing a node (tests/runner/test_ray_nodes.py): about a minute of
# waiting on nodes, kept out of `make test`'s 4 minutes; CI runs it after the suite.
test-cluster: $(STAMP)
	$(PY) -m pytest -q -m cluster tests/runner/test_ray_nodes.py

# The documentation site (mkdocs.yml) into site/: the [docs] extra goes into .venv beside
# what setup installs (not part of `make test`'s install). --strict: a warning fails the build
# (a broken link or anchor, a page missing from the nav, a public name of prsc without an API
# entry or a docstring: docs/hooks.py).
DOCS_STAMP := $(VENV)/.docs-installed
$(DOCS_STAMP): $(STAMP) pyproject.toml
	$(PY) -m pip install -q --no-compile -e '.[docs]'
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	NO_MKDOCS_2_WARNING=1 $(PY) -m mkdocs build --strict

# The Table-Cube spec -> 8 MuJoCo scenes: check it, compile it, load and step scene 0,
# and draw a contact sheet of all 8 (out/demo/table_cube_sheet.png). --force: a demo folder
# left by an older prsc (another law or model library) is replaced, only the files it listed.
demo: $(STAMP)
	$(PRSC) check specs/table_cube.prs
	$(PRSC) compile specs/table_cube.prs --target mjcf -n 8 --seed 0 -o out/demo --force
	$(PY) -m prsc.runner.settle_report out/demo/table_cube/mjcf/00000.xml
	$(PRSC) preview specs/table_cube.prs -n 8 --seed 0 -o out/demo/table_cube_sheet.png
	@echo "scenes: out/demo/table_cube/mjcf/*.xml   contact sheet: out/demo/table_cube_sheet.png"

# Every spec in specs/ into every format (the model library, tabletop.prs, is in prsc/library),
# each scene then stepped 1 s in MuJoCo: the settle check lists objects that do not rest
# where the scene says (exit 1, reported, not fatal: table_cube_naive's bare `on` may tip).
DATASET_SCENES ?= 100
DATASET_SPECS := $(wildcard specs/*.prs)
datasets: $(STAMP)
	@for spec in $(DATASET_SPECS); do echo "== $$spec"; \
	  $(PRSC) compile $$spec --target json,mjcf,urdf,sdf,usd -n $(DATASET_SCENES) --seed 0 -o out/datasets --jobs 2 \
	    --settle-check; rc=$$?; [ $$rc -le 1 ] || exit $$rc; done

# Samplers side by side (the paper's Table II), files written per second per format, then
# handover episodes per CPU-second (and where an episode's CPU time goes). Only the
# repository's own specs: a clone stands alone.
BENCH_SPECS := specs/table_cube.prs specs/table_cube_naive.prs
# Packed bins of parts of random size and yaw (issue 38): the joint law against the sequential one.
PACKED_SPECS := specs/bin_ten_parts.prs specs/bin_twenty_parts.prs
bench: $(STAMP)
	$(PRSC) bench $(BENCH_SPECS)
	$(PRSC) bench $(PACKED_SPECS) --samplers exact --laws joint,sequential --seconds 10
	$(PRSC) bench --backends specs/table_cube.prs -n 1000 --jobs 1,2
	$(PRSC) bench --episodes specs/table_cube.prs -n 21

# The paper's section IV case study: 100 Table-Cube episodes, table + plots in out/casestudy.
CASESTUDY := $(PRSC) run specs/table_cube.prs -n 100 --seed 0 --jobs 2
casestudy: $(STAMP)
	$(CASESTUDY) -o out/casestudy --video 4

# A second, independent run must reproduce every result except the wall-clock times.
casestudy-check: casestudy
	rm -rf out/casestudy-rerun
	$(CASESTUDY) -o out/casestudy-rerun
	$(PY) -c "import json, sys; f = lambda p: [{k: v for k, v in json.loads(l).items() if k != 'wall_seconds'} for l in open(p)]; same = f('out/casestudy/results.jsonl') == f('out/casestudy-rerun/results.jsonl'); print('casestudy reproduced exactly' if same else 'casestudy NOT reproduced'); sys.exit(0 if same else 1)"

clean:
	rm -rf build out site .pytest_cache

# `reachable by`: the library arm's top-down reach ring (built by the one builder, cached in the build folder),
# what it keeps of the true reach, and its edge checked against the IK; then the 200-episode demonstration (docs/assets.md).
.PHONY: reach reach-demo
reach: $(STAMP)
	$(PRSC) reach panda --edge-check
reach-demo: $(STAMP)
	$(PRSC) run specs/table_cube_reach.prs -n 200 --seed 0 --jobs 2 -o out/reach

# lerobot reads what `prsc run --record` writes (docs/datasets.md): lerobot 0.4.4 in its own venv
# (CPU torch 2.13.0 first, then lerobot without its pins of an older CUDA torch, then what its
# dataset reader imports), a 20-episode Franka pick dataset with a 128x128 camera, loaded by
# LeRobotDataset; then the suite's lerobot test with that venv. torchcodec decodes the videos
# with the system's FFmpeg 5.1 libraries (Debian: apt-get install libavutil57 libavcodec59
# libavformat59 libavdevice59 libavfilter8 libswscale6 libswresample4). Not part of `make test`.
LEROBOT_VENV := .lerobot-venv
LEROBOT_STAMP := $(LEROBOT_VENV)/.installed
LEROBOT_EPISODES ?= 20
PYBULLET_DATA = $$($(PY) -c 'import pybullet_data; print(pybullet_data.getDataPath())')
$(LEROBOT_STAMP):
	test -x $(LEROBOT_VENV)/bin/python || $(PYTHON) -m venv $(LEROBOT_VENV)
	$(LEROBOT_VENV)/bin/pip install -q torch==2.13.0
	$(LEROBOT_VENV)/bin/pip install -q --no-deps lerobot==0.4.4 torchcodec==0.13.0
	$(LEROBOT_VENV)/bin/pip install -q "datasets>=4.0.0,<5.0.0" "huggingface-hub>=0.34.2,<0.36.0" "av>=15.0.0,<16.0.0" \
	  "packaging>=24.2,<26.0" "accelerate>=1.10.0,<2.0.0" "numpy<2.4" pillow
	touch $(LEROBOT_STAMP)

lerobot-check: $(STAMP) $(LEROBOT_STAMP)
	$(PRSC) run specs/pybullet_arm/franka_pick_camera.prs --controller prsc.runner.pick:pick -n $(LEROBOT_EPISODES) \
	  --seed 0 --jobs 2 -I "$(PYBULLET_DATA)" -o out/lerobot-check/run --record out/lerobot-check/franka_pick
	$(LEROBOT_VENV)/bin/python tests/data/record/lerobot_load.py out/lerobot-check/franka_pick --item 0 \
	  | $(PY) -c "import json, sys; r = json.loads(sys.stdin.read()); print(r['episodes'], 'episodes,', r['frames'], 'frames,', len(r['features']), 'features read by lerobot'); sys.exit(r['episodes'] != $(LEROBOT_EPISODES))"
	$(PRSC) replay out/lerobot-check/franka_pick --episode 0
	PRSC_LEROBOT_PYTHON=$(LEROBOT_VENV)/bin/python $(PY) -m pytest -q tests/runner/test_datasets.py -k lerobot_loads
