"""Real-time factor of the engine with a crowd: 30 people walking (social force model) and the
360-beam LiDAR, against the same engine without people.

One model (Jackal in the seeded ``indoor`` world, 10 Hz control, 5 ms physics), two loops of
``Engine.step`` + ``Engine.scan`` (what the in-process transport does per step), run
interleaved, best of ``--repeat``: ``crowd`` with ``crowd.count`` 30 in groups of up to 3, and
``empty`` with none. The real-time factor is simulated seconds per wall second; the ratio
crowd ÷ empty says what the people cost. Issue 41's target: 30 people at >= 10 x real time.
The last lines are ``RESULT <name> <value>`` for ``docs/performance.md``.

    .venv/bin/python benchmarks/crowd_throughput.py
"""

from __future__ import annotations

import argparse

from _engine_rtf import best_rtf

from pic4rl_sim.engine.core import Engine
from pic4rl_sim.engine.crowd.params import CrowdParams
from pic4rl_sim.engine.engine_config import EngineConfig
from pic4rl_sim.engine.robot_specs import JACKAL
from pic4rl_sim.engine.worlds.generators import make_world


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--people", type=int, default=30)
    parser.add_argument("--steps", type=int, default=600, help="control steps per run")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    world = make_world("indoor", seed=0)
    crowd = Engine(JACKAL, world, EngineConfig(crowd=CrowdParams(count=args.people,
                                                                 max_group_size=3)), seed=0)
    empty = Engine(JACKAL, world, EngineConfig(), seed=0)
    best = best_rtf({"crowd": crowd, "empty": empty}, args.steps, args.repeat)
    print(f"crowd of {args.people}: {best['crowd']:.1f} x real time; no people: "
          f"{best['empty']:.1f} x; ratio {best['crowd'] / best['empty']:.2f}")
    print(f"RESULT crowd_empty_rtf {best['empty']:.1f}")
    print(f"RESULT crowd_ratio {best['crowd'] / best['empty']:.3f}")
    print(f"RESULT crowd_rtf_{args.people} {best['crowd']:.1f}")


if __name__ == "__main__":
    main()
