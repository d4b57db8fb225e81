# The README's two commands: `make demo` and `make test`. Both set up .venv/ first.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
# Message packages PyPI lacks (ros/<pkg>/: tf2_msgs, for the sim's /tf and /tf_static), built
# into the venv with PyPI's ament/rosidl generators by ros/build.sh (~20-30 s on 2 cores).
ROS_MSGS := $(VENV)/.ros_msgs
# DDS discovery stays on this machine (set ROS_DOMAIN_ID to keep parallel runs apart).
export ROS_AUTOMATIC_DISCOVERY_RANGE ?= LOCALHOST
export MPLBACKEND ?= Agg

.PHONY: setup demo test bench clean

setup: $(STAMP) $(ROS_MSGS)

# torch is pinned and installed first: an unpinned torch pulls several GB of CUDA packages.
$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet torch==2.13.0
	$(PY) -m pip install --quiet -e '.[all,test]'
	touch $(STAMP)

$(ROS_MSGS): $(STAMP) ros/build.sh $(wildcard ros/*/package.xml ros/*/CMakeLists.txt ros/*/msg/*.msg)
	ros/build.sh $(VENV)
	touch $(ROS_MSGS)

# The full loop: the shipped TD3-LiDAR agent (checkpoints/td3_lidar, the paper's observation),
# the best mapless agent (checkpoints/td3_lidar_explorer: TD3-LiDAR pointed along the mapless
# explorer's plan of its own scans) and four baselines (proportional, DWA, the privileged
# planner and the mapless explorer) on the paper's 5 indoor test pairs, each
# through the sim node over ROS 2 (pic4rl-run starts and stops it), one bag per episode under
# bags/demo*/, then the metrics table of those bags and a video of each episode beside its bag
# (bags/demo*/<agent>/episode_NNNN.mp4; the last line says where). `make demo TRAIN=1` trains
# TD3-LiDAR from scratch first (in process; see docs/results.md for how long) and tests that
# run instead.
# `make demo CASE=vineyard`: the paper's vineyard study (its section 4.2): the shipped depth
# agents (checkpoints/vineyard_{td3,sac}) and the two row followers (the privileged centre-line
# one and the classical one) on every lane of vineyard variant 101, rows no agent trained on,
# through the sim node over ROS 2; bags, table and videos under bags/demo_vineyard*/.
DEMO_RUN := demo_$(shell date +%Y%m%d-%H%M%S)
# `make demo CASE=person`: the person-monitoring RL-DWA hybrid (checkpoints/person_hybrid)
# against DWA with a proportional heading law, on person-world variants training never saw.
PERSON_DEMO := --agent checkpoints/person_hybrid --baseline dwa_heading \
	--sim-kwargs world_variant:101 --episodes 5 --seed 1000 --run demo_person --video
VINEYARD_LANES := build/vineyard_lanes_101.json
VINEYARD_DEMO := --agent checkpoints/vineyard_td3 --agent checkpoints/vineyard_sac \
	--baseline centerline --baseline row_follower --episodes 7 --sim-kwargs world_variant:101 \
	--env-kwargs episodes.file:$(VINEYARD_LANES) --run demo_vineyard --video
# `make demo CASE=barn`: the shipped BARN agent (checkpoints/barn_td3_explorer: mapless, learned
# on training worlds only) beside DWA and the privileged planner on 5 of BARN's 50 test worlds,
# one run each, through the sim node over ROS 2 (config/suite_barn_demo.yaml): a bag per
# episode, the BARN table (bags/demo_barn/results.md) and a video per bag in bags/demo_barn/videos/.
BARN_DEMO := bags/demo_barn
# `make demo CASE=crowd`: the shipped TD3-LiDAR agent, DWA and ORCA on the paper's 5 indoor test
# pairs among 10 walking people, in process (config/suite_crowd_demo.yaml, a cut of
# config/suite_crowd.yaml): a bag per episode, the table with the social columns and the report
# (bags/demo_crowd/results.md, report.html) and a video per bag, the people drawn with their
# tracks' tails (bags/demo_crowd/videos/).
CROWD_DEMO := bags/demo_crowd
# `make demo CASE=explore`: the learned frontier choice (frontier_ppo) and the two exploration
# baselines, frontier and random walk, on a held-out indoor world and two held-out layouts of the
# larger house, in process (config/suite_explore_demo.yaml): a bag per episode, the explore table
# (coverage %, times to 50 % and 90 %; bags/demo_explore/results.md), the report with the
# coverage curves (bags/demo_explore/report.html) and a video per bag shading the floor seen
# (bags/demo_explore/videos/).
EXPLORE_DEMO := bags/demo_explore
# `make demo CASE=sensors`: the fusion study's agents in the clutter3d world (low boxes below the
# LiDAR's plane, tables and shelves on thin legs): LiDAR-only, depth-only and fused
# (checkpoints/fusion_*), and the explorer on the fused grid, on 5 test layouts training never
# saw, through the sim node over ROS 2 (config/suite_fusion_demo.yaml): a bag per episode, the
# table (bags/demo_sensors/results.md) and a video per bag (bags/demo_sensors/videos/).
SENSORS_DEMO := bags/demo_sensors
demo: setup
ifeq ($(CASE),barn)
	$(VENV)/bin/pic4rl-bench --no-progress config/suite_barn_demo.yaml
	$(VENV)/bin/pic4rl-metrics video --no-progress --out $(BARN_DEMO)/videos $(BARN_DEMO)
else ifeq ($(CASE),crowd)
	$(VENV)/bin/pic4rl-bench --no-progress config/suite_crowd_demo.yaml
	$(VENV)/bin/pic4rl-metrics video --no-progress --out $(CROWD_DEMO)/videos $(CROWD_DEMO)
else ifeq ($(CASE),explore)
	$(VENV)/bin/pic4rl-bench --no-progress config/suite_explore_demo.yaml
	$(VENV)/bin/pic4rl-metrics video --no-progress --out $(EXPLORE_DEMO)/videos $(EXPLORE_DEMO)
else ifeq ($(CASE),sensors)
	$(VENV)/bin/pic4rl-bench --no-progress config/suite_fusion_demo.yaml
	$(VENV)/bin/pic4rl-metrics video --no-progress --out $(SENSORS_DEMO)/videos $(SENSORS_DEMO)
else ifeq ($(CASE),person)
	$(VENV)/bin/pic4rl-run test $(PERSON_DEMO)
else ifeq ($(CASE),vineyard)
	mkdir -p build && $(PY) tools/vineyard_lanes.py config/train_vineyard_sac.yaml 101 -o $(VINEYARD_LANES)
	$(VENV)/bin/pic4rl-run test $(VINEYARD_DEMO)
else ifdef TRAIN
	$(VENV)/bin/pic4rl-train --run $(DEMO_RUN) --ros-args --params-file config/train_goto_lidar_td3.yaml
	$(VENV)/bin/pic4rl-run test --agent td3_lidar=runs/$(DEMO_RUN) --baseline proportional --baseline dwa --baseline planner --run demo --video
else
	$(VENV)/bin/pic4rl-run test --agent checkpoints/td3_lidar --agent checkpoints/td3_lidar_explorer --baseline proportional --baseline dwa --baseline planner --baseline explorer --run demo --video
endif

test: setup
	$(PY) -m pytest -q

bench: setup
	$(PY) benchmarks/metrics_throughput.py
	$(PY) benchmarks/sim_throughput.py
	$(PY) benchmarks/env_throughput.py
	$(PY) benchmarks/train_throughput.py
	$(PY) benchmarks/video_throughput.py

clean:
	rm -rf $(VENV) build *.egg-info
