"""``reader``: the time base (headerless messages placed by the pose topic's offset), a killed
recorder's bag and MCAP read like a finished sqlite3 bag.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from metrics_helpers import EXACT, F32, LINE, NS
from metrics_helpers import rewrite as _rewrite
from metrics_helpers import row as _row
from metrics_helpers import same as _same

from pic4rl_metrics import (
    Footprint,
    compute,
    compute_metrics,
    read_episode,
)
from pic4rl_metrics.synthetic.synthetic import (
    DEFAULT_T0_NS,
    Obstacles,
    write_episode_bag,
)

# --- time base -----------------------------------------------------------------------------


def test_headerless_outcome_word_is_placed_by_the_pose_offset(tmp_path: Path) -> None:
    # Receive times run 1000 s ahead of the header stamps; the bare word "goal" arrives at
    # receive time t0 + 1000 s + 7 s, i.e. 7 s into the episode on the header time base.
    offset = 1000 * NS
    src = write_episode_bag(tmp_path / "src", LINE, goal=(5.0, 0.0), outcome="goal",
                            receive_offset_ns=offset)
    bag = _rewrite(src, tmp_path / "word", outcome_word_recv_ns=DEFAULT_T0_NS + offset + 7 * NS)
    m = _row(bag)
    assert m["outcome"] == "goal"
    assert m["clearance_time_s"] == pytest.approx(7.0, abs=EXACT)

@pytest.mark.parametrize("stamped", [False, True])
def test_headerless_cmd_vel_lands_on_the_header_time_base(tmp_path: Path, stamped: bool) -> None:
    bag = write_episode_bag(
        tmp_path / "offset", LINE, cmd_stamped=stamped, receive_offset_ns=1000 * NS
    )
    ep = read_episode(bag)
    assert ep.cmd is not None and len(ep.cmd) == len(ep.pose)
    assert abs(int(ep.cmd.t_ns[0]) - int(ep.pose.t_ns[0])) <= 1_000_000  # within 1 ms
    assert abs(int(ep.cmd.t_ns[-1]) - int(ep.pose.t_ns[-1])) <= 1_000_000
    assert int(ep.pose.t_ns[0]) == DEFAULT_T0_NS  # header stamps, not receive times
    assert compute_metrics(ep).clearance_time_s == pytest.approx(10.0, abs=EXACT)

# --- storage: killed recorder, MCAP ------------------------------------------------------------

FACTS = {"agent": "td3", "run": "r1", "episode": "3", "footprint": {"radius_m": 0.2}}
SCENE = Obstacles(circles=((2.5, 0.8, 0.3),), segments=((-1.0, -1.0, 8.0, -1.0),))


def _episode_kwargs() -> dict[str, object]:
    return {"obstacles": SCENE, "goal": (5.0, 0.0), "facts": FACTS, "outcome": "goal"}


def _assert_same_rows(a: dict[str, object], b: dict[str, object]) -> None:
    differ = {k: (a[k], b[k]) for k in a if k != "bag" and not _same(a[k], b[k])}
    assert differ == {}


def test_killed_recorder_gives_the_same_row(tmp_path: Path) -> None:
    full = write_episode_bag(tmp_path / "full", LINE, **_episode_kwargs())
    killed = write_episode_bag(
        tmp_path / "bags" / "killed", LINE, write_metadata=False, **_episode_kwargs()
    )
    files = sorted(p.name for p in killed.iterdir())
    assert files == ["killed.db3"]
    reference = _row(full)
    assert reference["outcome"] == "goal"
    assert not math.isnan(reference["collision_count"])  # the footprint was there
    _assert_same_rows(reference, _row(killed / "killed.db3"))
    globbed = compute([str(tmp_path / "bags" / "*" / "*.db3")]).frame
    assert len(globbed) == 1
    _assert_same_rows(reference, globbed.iloc[0].to_dict())
    # The facts came from the facts topic (custom_data lived in the lost metadata.yaml).
    ep = read_episode(killed / "killed.db3")
    assert ep.facts.agent == "td3" and ep.facts.run == "r1"
    assert ep.facts.goal == (5.0, 0.0)
    assert ep.facts.footprint == Footprint(radius_m=0.2)


def test_mcap_gives_the_same_metrics_as_sqlite3(tmp_path: Path) -> None:
    sqlite = write_episode_bag(tmp_path / "sqlite", LINE, **_episode_kwargs())
    mcap = write_episode_bag(tmp_path / "mcap", LINE, storage="mcap", **_episode_kwargs())
    assert any(p.suffix == ".mcap" for p in mcap.iterdir())
    a, b = _row(sqlite), _row(mcap)
    _assert_same_rows(a, b)
    # The cylinder (2.5, 0.8, r 0.3) passes 0.8 - 0.3 = 0.5 m to the left at x = 2.5.
    assert a["obstacle_dist_min_m"] == pytest.approx(0.5, abs=F32)
