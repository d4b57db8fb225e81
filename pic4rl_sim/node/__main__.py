"""``python -m pic4rl_sim.node``: the sim node, as ``pic4rl-sim``."""

import sys

from .sim_node import main

sys.exit(main())
