# prsc build: every target sets up .venv itself when it is missing.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
PRSC := $(VENV)/bin/prsc
STAMP := $(VENV)/.installed
export MUJOCO_GL ?= egl
export PYOPENGL_PLATFORM ?= egl

.PHONY: setup test demo datasets bench casestudy casestudy-check clean

setup: $(STAMP)

# --no-compile: pip byte-compiles every module it installs (23 of 53 s of a fresh install
# here); Python compiles the ones a command imports on first use instead (about 5 s).
$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q --no-compile -e '.[dev,ray,gym]'
	touch $(STAMP)

test: $(STAMP)
	$(PY) -m pytest -q -n 2 --dist loadfile

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
	rm -rf build out .pytest_cache

# `reachable by`: regenerate the Panda's top-down reachable set from its IK (~11 min on 2 cores), measure
# what it keeps of the true reach and of a tray, check its edge; then the 200-episode demonstration (docs/sampling.md).
.PHONY: reach reach-demo
reach: $(STAMP)
	$(PY) -m prsc.commands.reach --jobs 2
	$(PY) -m prsc.commands.reach --coverage --jobs 2
	$(PY) -m prsc.commands.reach --tray-report specs/table_cube_reach.prs --jobs 2
	$(PY) -m prsc.commands.reach --edge-check --jobs 2
reach-demo: $(STAMP)
	$(PRSC) run specs/table_cube_reach.prs -n 200 --seed 0 --jobs 2 -o out/reach
