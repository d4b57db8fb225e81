"""How far configuration travels before it is resolved (issue 39 item 2's measure), by
following the calls: ``make_vec_env(n_envs=2)`` on a shipped training config, in this process
(``vec_env=dummy``), under ``sys.settrace``.

Every call of a package function (``pic4rl_*``) is classed by what it receives: configuration
still to resolve (an ``EnvConfig``, or a dict of params: the sim section, a params file's
section), typed values only (a ``Scenario``, ``SimConfig``, ``RobotInfo``, a robot or world
spec, a config's typed sub-section), or neither. A call goes back up when the caller's module
is in a lower layer than the callee's (base < sim, metrics < the bridge's rooms, bottom to
top as ``tests/bridge/test_layers.py`` stacks them < agents) and the callee receives
configuration to resolve. Calls into the sim's configuration (``pic4rl_sim.config``) are
counted apart (resolved once, there is one ``build_config``), and so are the executed lines
that read the raw sim section (``.sim_params``) again.

    python tools/config_trace.py [--root TREE] [--config config/train_goto_lidar_td3.yaml]

``--root`` measures another checkout (a ``git worktree`` of an older commit); the printed
JSON has the counts and the lists behind them.
"""

from __future__ import annotations

import argparse
import json
import linecache
import sys
from collections import defaultdict
from collections.abc import Mapping
from pathlib import Path
from typing import Any

#: Layers, bottom to top, by module prefix (the longest prefix wins).
LAYERS: tuple[tuple[str, ...], ...] = (
    ("pic4rl_base",),
    ("pic4rl_sim", "pic4rl_metrics"),
    ("pic4rl_bridge.errors", "pic4rl_bridge.settings", "pic4rl_bridge.config",
     "pic4rl_bridge.robot_info", "pic4rl_bridge.scenario", "pic4rl_bridge.readings"),
    ("pic4rl_bridge.perception",),
    ("pic4rl_bridge.control",),
    ("pic4rl_bridge.baselines",),
    ("pic4rl_bridge.tasks",),
    ("pic4rl_bridge.transports",),
    ("pic4rl_bridge",),
    ("pic4rl_agents",),
)
#: Modules that define and resolve configuration (they receive it by their nature).
MACHINERY = ("pic4rl_base.params_file", "pic4rl_base.param_types", "pic4rl_base.schema",
             "pic4rl_bridge.config", "pic4rl_bridge.settings", "pic4rl_sim.config",
             "pic4rl_agents.runs.config")
#: Types whose instances are resolved, typed values.
TYPED = ("Scenario", "SimConfig", "RobotInfo", "RobotSpec", "WorldSpec")


def layer(module: str) -> int:
    best, index = -1, -1
    for i, members in enumerate(LAYERS):
        for m in members:
            if (module == m or module.startswith(m + ".")) and len(m) > best:
                best, index = len(m), i
    return index


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=str(Path(__file__).resolve().parents[1]))
    parser.add_argument("--config", default="config/train_goto_lidar_td3.yaml")
    args = parser.parse_args()
    root = Path(args.root).resolve()
    sys.path.insert(0, str(root))

    from pic4rl_agents.runs.config import NODES, run_config
    from pic4rl_agents.training import envs
    from pic4rl_base import params_file
    from pic4rl_bridge.config import EnvConfig

    if not Path(envs.__file__).resolve().is_relative_to(root):
        raise SystemExit(f"{envs.__file__}: imported from outside {root}")
    file = str(root / args.config)
    env = run_config(params_file.load([file], NODES), [file]).env
    keys = set(env.sim_params) | set(env.to_params())

    def kind(value: Any) -> str:
        if isinstance(value, EnvConfig):
            return "raw"
        if isinstance(value, Mapping) and value and all(isinstance(k, str) for k in value) \
                and keys & set(value):
            return "dict"
        cls = type(value)
        if cls.__name__ in TYPED or (cls.__module__.startswith(MACHINERY)
                                     and hasattr(value, "__dataclass_fields__")):
            return "typed"
        return ""

    raw_fns: dict[str, set[str]] = defaultdict(set)  # function -> caller sites
    raw_calls = [0]
    dict_fns: set[str] = set()  # those given a params dict (the sim section, a file's)
    typed_fns: set[str] = set()
    up: set[str] = set()
    sim_config: dict[str, int] = defaultdict(int)
    sim_reads: set[str] = set()  # executed lines that read the raw sim section
    prefix = str(root) + "/"

    def lines(frame: Any, event: str, _arg: Any) -> Any:
        if event == "line":
            text = linecache.getline(frame.f_code.co_filename, frame.f_lineno)
            if ".sim_params" in text:
                sim_reads.add(f"{frame.f_globals['__name__']}:{frame.f_lineno}")
        return lines

    def trace(frame: Any, event: str, _arg: Any) -> Any:
        if event != "call" or not frame.f_code.co_filename.startswith(prefix):
            return None
        module = frame.f_globals.get("__name__", "")
        if not module.startswith("pic4rl_"):
            return None
        calls(frame, module)
        return lines

    def calls(frame: Any, module: str) -> None:
        code = frame.f_code
        names = code.co_varnames[:code.co_argcount + code.co_kwonlyargcount]
        kinds = {kind(frame.f_locals.get(n)) for n in names if n not in ("self", "cls")}
        fn = f"{module}.{code.co_qualname}"
        caller = frame.f_back
        cmod = caller.f_globals.get("__name__", "") if caller else ""
        site = f"{cmod}:{caller.f_lineno}" if caller else "?"
        if code.co_name == "<module>":
            return
        if module.startswith("pic4rl_sim.config") and not cmod.startswith("pic4rl_sim"):
            sim_config[fn] += 1
        if kinds & {"raw", "dict"}:
            if "dict" in kinds:
                dict_fns.add(fn)
            raw_fns[fn].add(site)
            raw_calls[0] += 1
            if cmod.startswith("pic4rl_") and layer(cmod) < layer(module):
                up.add(f"{site} -> {fn}")
        elif "typed" in kinds:
            typed_fns.add(fn)

    sys.settrace(trace)
    try:
        vec = envs.make_vec_env(env, n_envs=2, seed=0, vec_env="dummy")
    finally:
        sys.settrace(None)
    vec.close()

    def files(fns: Any) -> set[str]:
        return {sys.modules[_module_of(f)].__file__ for f in fns}

    outside = {f: s for f, s in raw_fns.items() if not _module_of(f).startswith(MACHINERY)}
    print(json.dumps({
        "root": str(root), "config": args.config,
        "raw_functions": len(raw_fns), "raw_files": len(files(raw_fns)),
        "raw_call_sites": sum(len(s) for s in raw_fns.values()), "raw_calls": raw_calls[0],
        "raw_functions_outside_machinery": len(outside),
        "raw_files_outside_machinery": len(files(outside)),
        "raw_call_sites_outside_machinery": sum(len(s) for s in outside.values()),
        "dict_functions_outside_machinery": sorted(
            f for f in dict_fns if not _module_of(f).startswith(MACHINERY)),
        "sim_section_reads": sorted(sim_reads),
        "sim_section_reads_outside_machinery": len(
            [r for r in sim_reads if not r.startswith(MACHINERY)]),
        "typed_only_functions": len(typed_fns), "back_up": len(up),
        "sim_config_calls": dict(sim_config),
        "raw": {f: sorted(s) for f, s in sorted(raw_fns.items())},
        "up": sorted(up)}, indent=1))


def _module_of(fn: str) -> str:
    """The module of ``module.qualname`` (the longest prefix that is an imported module)."""
    parts = fn.split(".")
    for end in range(len(parts), 0, -1):
        if ".".join(parts[:end]) in sys.modules:
            return ".".join(parts[:end])
    return fn


if __name__ == "__main__":
    main()
