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

# Until the sim and agents exist: example episode bags of our own making, then their metrics.
demo: setup
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
