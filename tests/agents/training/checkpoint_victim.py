"""``pic4rl-train`` that kills itself (SIGKILL) halfway through writing a file of its second
checkpoint, as a power cut or the OOM killer would (test_agents_checkpoints' kill test).

Usage: ``python checkpoint_victim.py pkl|zip PIC4RL_TRAIN_ARGS...``: ``pkl`` dies in the
replay buffer's write, ``zip`` in the model's. The file SB3 was writing is left with half of
its bytes, then the process is killed.
"""

from __future__ import annotations

import os
import signal
import sys
from pathlib import Path
from typing import Any

from stable_baselines3.common import base_class, off_policy_algorithm

from pic4rl_agents.training import train


def main() -> None:
    what, argv = sys.argv[1], sys.argv[2:]
    module, name = ((off_policy_algorithm, "save_to_pkl") if what == "pkl"
                    else (base_class, "save_to_zip_file"))
    real = getattr(module, name)
    calls: list[Any] = []

    def dying(path: Any, *args: Any, **kwargs: Any) -> None:
        calls.append(path)
        real(path, *args, **kwargs)
        if len(calls) == 2:
            data = Path(path).read_bytes()
            Path(path).write_bytes(data[: len(data) // 2])
            os.kill(os.getpid(), signal.SIGKILL)

    setattr(module, name, dying)
    sys.exit(train.main(argv))


if __name__ == "__main__":
    main()
