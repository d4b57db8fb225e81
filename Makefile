# The README's two commands: `make demo` and `make test`. Both set up .venv/ first.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
# A fresh ROS 2 domain per run keeps DDS traffic of parallel runs apart.
export ROS_AUTOMATIC_DISCOVERY_RANGE ?= LOCALHOST
export MPLBACKEND ?= Agg

.PHONY: setup demo test bench clean

setup: $(STAMP)

# torch is pinned and installed first: an unpinned torch pulls several GB of CUDA packages.
$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet torch==2.13.0
	$(PY) -m pip install --quiet -e '.[all,test]'
	touch $(STAMP)

# Until trained agents exist: episodes of the proportional baseline through the env (in-process
# MuJoCo sim, recorded to bags/demo_proportional, appended on each run), then the metrics of
# those bags; and example episode bags of our own making with their metrics and plots.
demo: setup
	$(PY) -m pic4rl_bridge.demo --episodes 5 --bags bags --run demo_proportional
	$(VENV)/bin/pic4rl-metrics compute bags/demo_proportional --format table
	$(PY) -m pic4rl_metrics.examples bags/example
	$(VENV)/bin/pic4rl-metrics compute bags/example --format table
	$(VENV)/bin/pic4rl-metrics compare bags/example --format markdown
	$(VENV)/bin/pic4rl-metrics plot bags/example --out bags/example/plots

test: setup
	$(PY) -m pytest -q

bench: setup
	$(PY) benchmarks/metrics_throughput.py
	$(PY) benchmarks/sim_throughput.py
	$(PY) benchmarks/env_throughput.py

clean:
	rm -rf $(VENV) build *.egg-info
