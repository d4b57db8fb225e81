"""One ``ConfigError`` for every package: the shared base defines it (``pic4rl_base.errors``),
the metrics, the sim and the bridge re-export it, so a bad value met anywhere below ``pic4rl-test`` or ``pic4rl-train``
(the bag contract's checks inside ``NavEnv`` included) is one line and exit 2."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import pytest
from agents_helpers import LIDAR_TD3

import pic4rl_base.errors
import pic4rl_bridge.errors
import pic4rl_metrics
import pic4rl_metrics.errors
import pic4rl_sim.errors
from pic4rl_agents.testing import tester
from pic4rl_agents.training import train

# What the bag contract says of a bad fact (pic4rl_metrics.contract.Outcome.parse).
MESSAGE = "outcome: 'won' is not an outcome; expected one of goal, collision, timeout"


def test_every_package_names_the_same_class() -> None:
    one = pic4rl_base.errors.ConfigError
    assert pic4rl_metrics.errors.ConfigError is one
    assert pic4rl_sim.errors.ConfigError is one
    assert pic4rl_bridge.errors.ConfigError is one
    assert pic4rl_metrics.ConfigError is one
    # what a console script catches as bad input: every package's own errors too
    assert issubclass(one, pic4rl_base.errors.Pic4rlError)
    assert issubclass(pic4rl_metrics.errors.MetricsError, pic4rl_base.errors.Pic4rlError)


def _main(main, argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def _raise(*_args, **_kwargs):
    raise pic4rl_metrics.errors.ConfigError(MESSAGE)


@pytest.mark.bad_input
def test_pic4rl_test_reports_the_metrics_config_error_in_one_line(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(tester, "drive_and_judge", _raise)
    code, out, err = _main(tester.main, [
        "--baseline", "proportional", "--bags", str(tmp_path / "bags"), "--no-progress",
        "--ros-args", "--params-file", str(LIDAR_TD3)])
    assert (code, out, err) == (2, "", f"pic4rl-test: {MESSAGE}\n")


@pytest.mark.bad_input
def test_pic4rl_train_reports_the_metrics_config_error_in_one_line(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(train, "Trainer", _raise)
    code, out, err = _main(train.main, ["--no-progress", "--ros-args", "--params-file",
                                        str(LIDAR_TD3)])
    assert (code, err) == (2, f"pic4rl-train: {MESSAGE}\n")
