"""Real-time factor of the engine in the dynamic BARN: ``dynbarn``'s moving obstacles and the
LiDAR, against the same field standing still.

One model (Jackal in ``dynbarn`` variant 1 with 12 moving cylinders (``--moving``), 10 Hz control,
5 ms physics), two loops of ``Engine.step`` + ``Engine.scan`` (what the in-process transport
does per step), run interleaved, best of ``--repeat``: ``moving`` and ``still`` (the same world
with ``moving_count`` 0). The real-time factor is simulated seconds per wall second; the ratio
moving ÷ still says what the motion costs. The last lines are ``RESULT <name> <value>`` for
``docs/performance.md``.

    .venv/bin/python benchmarks/dynbarn_throughput.py
"""

from __future__ import annotations

import argparse

from _engine_rtf import best_rtf

from pic4rl_sim.engine.core import Engine
from pic4rl_sim.engine.robot_specs import JACKAL
from pic4rl_sim.engine.worlds.generators import make_world


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moving", type=int, default=12, help="moving obstacles")
    parser.add_argument("--steps", type=int, default=600, help="control steps per run")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    engines = {"moving": Engine(JACKAL, make_world("dynbarn", seed=1, moving_count=args.moving)),
               "still": Engine(JACKAL, make_world("dynbarn", seed=1, moving_count=0))}
    best = best_rtf(engines, args.steps, args.repeat)
    ratio = best["moving"] / best["still"]
    print(f"dynbarn, {args.moving} moving: {best['moving']:.1f} x real time; still: "
          f"{best['still']:.1f} x; ratio {ratio:.2f}")
    print(f"RESULT dynbarn_still_rtf {best['still']:.1f}")
    print(f"RESULT dynbarn_ratio {ratio:.3f}")
    print(f"RESULT dynbarn_rtf {best['moving']:.1f}")


if __name__ == "__main__":
    main()
