"""How fast episodes become videos, and what rendering costs the env when it is off.

**Videos.** A 30 s sim-shaped episode bag (poses at 20 Hz, 360-beam scans at 10 Hz, a walled
12 m arena) rendered to MP4 at 10 fps on one core (this process and its ffmpeg pinned to
one CPU), from reading the bag to the closed file, side by side with the plain way to make the
same video: a matplotlib figure redrawn for every frame (path, scan, robot, cursor updated,
``canvas.draw()``) into the same ffmpeg. Target (issue 20): at least 10x faster than real time.

**Rendering off.** Env steps (goToPose LiDAR, in process, the robot turning on the spot) with
``render_mode=None``, against the same loop on the bridge as it was before rendering existed
(``--against REV``, default: the parent of the commit that gave ``NavEnv`` its render modes;
with the sim and metrics of that revision, which that bridge runs on; both in fresh
processes, interleaved). Target: less than 2 % of the env step time. Also the
cost of the step's one render hook alone (timed directly), of tracking the path with
``render_mode="rgb_array"``, and of rendering every step as ``RecordVideo`` does.

    .venv/bin/python benchmarks/video_throughput.py

The last lines are ``RESULT <name> <value>``, one per figure, for docs/performance.md.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tarfile
import tempfile
import time
import timeit
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

# The metrics load in the functions that use them: the env worker runs this file on an older
# revision's packages (``old_packages``), whose metrics had other module paths.
REPO = Path(__file__).resolve().parents[1]
CONFIG = REPO / "config" / "env_goto_lidar.yaml"
FPS = 10.0
TURN = np.array([-1.0, 0.5], dtype=np.float32)


def episode_bag(folder: Path, seconds: float) -> Path:
    from pic4rl_metrics.synthetic.synthetic import Obstacles, circle, write_episode_bag

    arena = Obstacles(
        circles=((6.0, 6.0, 0.5), (1.5, 1.5, 0.3), (10.5, 1.5, 0.3), (1.5, 10.5, 0.3)),
        segments=((0, 0, 12, 0), (12, 0, 12, 12), (12, 12, 0, 12), (0, 12, 0, 0)),
    )
    track = circle(3.0, 0.6, seconds, 0.05, center=(6.0, 6.0))
    facts = {"agent": "bench", "footprint": {"length_m": 0.508, "width_m": 0.430},
             "start": [6.0, 3.0, 0.0], "goal": [9.0, 6.0]}
    return write_episode_bag(folder / "episode", track, obstacles=arena, scan_every=2,
                             goal=(9.0, 6.0), facts=facts, outcome="timeout")


def ours(bag: Path, out: Path, seconds: float) -> float:
    from pic4rl_metrics.viz.video import VideoOptions, frame_count
    from pic4rl_metrics.viz.video_batch import render_videos

    start = time.perf_counter()
    rows = render_videos([bag], out, options=VideoOptions(fps=FPS), overwrite=True)
    took = time.perf_counter() - start
    assert not rows[0].error and rows[0].frames == frame_count(seconds, VideoOptions(fps=FPS))
    return took


def matplotlib_frames(bag: Path, seconds: float):  # noqa: ANN201 - a generator of frames
    """The plain way: one figure, its artists updated and the canvas redrawn every frame."""
    from pic4rl_metrics import read_episode
    from pic4rl_metrics.viz.plots import scan_hits_world
    from pic4rl_metrics.viz.video import VideoOptions, frame_count

    ep = read_episode(bag, full_scans=True)
    t = (ep.pose.t_ns - ep.pose.t_ns[0]) / 1e9
    rows, sx, sy = scan_hits_world(ep)
    ts = (ep.scan.t_ns[rows] - ep.pose.t_ns[0]) / 1e9
    fig = Figure(figsize=(9.6, 5.76), dpi=100, layout="constrained")
    canvas = FigureCanvasAgg(fig)
    ax, ax_v = fig.subplots(1, 2, width_ratios=[1.6, 1])
    ax.set_xlim(-1, 13), ax.set_ylim(-1, 13), ax.set_aspect("equal")
    path, = ax.plot([], [], color="tab:orange")
    scan = ax.scatter([], [], s=4, c="tab:red")
    robot, = ax.plot([], [], "s", ms=8)
    ax_v.plot(t, np.hypot(ep.pose.vx, ep.pose.vy))
    cursor = ax_v.axvline(0, color="black")
    for k in range(frame_count(seconds, VideoOptions(fps=FPS))):
        now = min((k + 1) / FPS, t[-1])
        i = int(np.searchsorted(t, now, side="right"))
        j = max(int(np.searchsorted(ts, now, side="right")) - 1, 0)
        path.set_data(ep.pose.x[:i], ep.pose.y[:i])
        scan.set_offsets(np.column_stack([sx[j], sy[j]]))
        robot.set_data([ep.pose.x[i - 1]], [ep.pose.y[i - 1]])
        cursor.set_xdata([now, now])
        canvas.draw()
        yield np.asarray(canvas.buffer_rgba())[..., :3]


def plain(bag: Path, out: Path, seconds: float) -> float:
    from pic4rl_metrics.viz.video_batch import write_video

    start = time.perf_counter()
    write_video(matplotlib_frames(bag, seconds), out / "plain.mp4", fps=FPS, overwrite=True)
    return time.perf_counter() - start


def env_loop(env, steps: int) -> float:  # noqa: ANN001
    env.reset(seed=0)
    start = time.perf_counter()
    for _ in range(steps):
        env.step(TURN)
    return time.perf_counter() - start


def env_worker(steps: int, repeat: int) -> None:
    """Print how many render modes this ``NavEnv`` has, and the best seconds of ``repeat``
    loops of ``steps`` steps with rendering off."""
    from pic4rl_bridge.env import NavEnv

    # the env file of this tree (the working folder: the old tree's own, whose keys it knows)
    env = NavEnv(CONFIG.relative_to(REPO), transport="inprocess",
                 overrides={"episode_max_steps": steps})
    best = min(env_loop(env, steps) for _ in range(repeat))
    print(len(NavEnv.metadata["render_modes"]), best)
    env.close()


def base_revision(against: str | None) -> str | None:
    if against:
        return against
    done = subprocess.run(["git", "log", "-S", '"render_modes": []', "--format=%H", "--",
                           "pic4rl_bridge/env.py"], cwd=REPO, capture_output=True, text=True,
                          check=False)
    commits = done.stdout.split()
    return f"{commits[0]}^" if done.returncode == 0 and commits else None


def old_packages(rev: str, folder: Path) -> Path:
    """The bridge and the packages it runs on (sim, metrics) and its env file at ``rev``,
    unpacked into ``folder``: an old bridge does not run on today's sim, metrics or keys."""
    archive = folder / "old.tar"
    subprocess.run(["git", "archive", "-o", str(archive), rev, "pic4rl_bridge", "pic4rl_sim",
                    "pic4rl_metrics", str(CONFIG.relative_to(REPO))], cwd=REPO, check=True)
    with tarfile.open(archive) as tar:
        tar.extractall(folder / "old", filter="data")
    return folder / "old"


def worker_s(pythonpath: list[Path], steps: int, repeat: int, *, modes: int) -> float:
    """A fresh process's best loop time, its bridge the first on ``pythonpath``, checked to
    have ``modes`` render modes (0: before rendering)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(str(p) for p in pythonpath))
    done = subprocess.run([sys.executable, __file__, "--env-worker", "--steps", str(steps),
                           "--repeat", str(repeat)], env=env, capture_output=True, text=True,
                          check=True, timeout=600, cwd=pythonpath[0])
    found, best = done.stdout.split()[-2:]
    assert int(found) == modes, f"the worker imported the wrong bridge ({found} render modes)"
    return float(best)


def env_figures(args: argparse.Namespace, folder: Path) -> dict[str, float]:
    from pic4rl_bridge.env import NavEnv

    over = {"episode_max_steps": args.steps}
    envs = {mode: NavEnv(CONFIG, transport="inprocess", overrides=over, render_mode=mode)
            for mode in (None, "rgb_array")}
    tracking = {"off": lambda: env_loop(envs[None], args.steps),
                "tracking": lambda: env_loop(envs["rgb_array"], args.steps)}
    best = dict.fromkeys([*tracking, "every_step"], float("inf"))
    for _ in range(args.repeat):
        for name, loop in tracking.items():
            best[name] = min(best[name], loop())
        env = envs["rgb_array"]
        env.reset(seed=0)
        start = time.perf_counter()
        for _ in range(args.steps):
            env.step(TURN)
            env.render()
        best["every_step"] = min(best["every_step"], time.perf_counter() - start)
    hook = envs[None]
    hook_s = min(timeit.repeat("if env._view is not None: env._view.track(None)",
                               globals={"env": hook}, number=100_000, repeat=5)) / 100_000
    for env in envs.values():
        env.close()
    step_s = best["off"] / args.steps
    figures = {"env_step_us": step_s * 1e6, "env_render_hook_ns": hook_s * 1e9,
               "env_render_hook_overhead": hook_s / step_s,
               "env_render_tracking_overhead": best["tracking"] / best["off"] - 1,
               "env_render_every_step_overhead": best["every_step"] / best["off"] - 1}
    rev = base_revision(args.against)
    if rev is not None:
        old = old_packages(rev, folder)
        new_s = old_s = float("inf")
        for _ in range(args.rounds):
            old_s = min(old_s, worker_s([old, REPO], args.steps, args.repeat, modes=0))
            new_s = min(new_s, worker_s([REPO], args.steps, args.repeat, modes=1))
        figures["env_steps_per_s_before_render"] = args.steps / old_s
        figures["env_steps_per_s_render_off"] = args.steps / new_s
        figures["env_render_off_overhead"] = new_s / old_s - 1
    return figures


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=3, help="best of this many runs")
    parser.add_argument("--episode-s", type=float, default=30.0, help="the episode's length")
    parser.add_argument("--steps", type=int, default=2000, help="env steps per timed loop")
    parser.add_argument("--rounds", type=int, default=3,
                        help="interleaved before/after env processes")
    parser.add_argument("--against", help="the bridge's revision before rendering (git)")
    parser.add_argument("--env-worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.env_worker:
        env_worker(args.steps, args.repeat)
        return 0
    os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[-1]})  # one core, ffmpeg too
    with tempfile.TemporaryDirectory(prefix="video_throughput_") as tmp:
        folder = Path(tmp)
        seconds = args.episode_s
        bag = episode_bag(folder, seconds)
        best = {"ours": float("inf"), "plain": float("inf")}
        for _ in range(args.repeat):
            best["ours"] = min(best["ours"], ours(bag, folder / "v", seconds))
            best["plain"] = min(best["plain"], plain(bag, folder / "v", seconds))
        figures = {"video_episode_s": seconds, "video_render_s": best["ours"],
                   "video_realtime_factor": seconds / best["ours"],
                   "video_matplotlib_per_frame_s": best["plain"],
                   "video_vs_matplotlib_ratio": best["plain"] / best["ours"]}
        figures.update(env_figures(args, folder))
    title = f"video of a {seconds:g} s episode, 10 fps, one core"
    print(f"{title:<44} {'ours':>9} {'matplotlib':>11}")
    print(f"{'  seconds':<44} {best['ours']:>9.2f} {best['plain']:>11.2f}")
    print(f"{'  x real time':<44} {seconds / best['ours']:>9.1f} "
          f"{seconds / best['plain']:>11.1f}")
    for name, value in figures.items():
        print(f"RESULT {name} {value:.4g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
