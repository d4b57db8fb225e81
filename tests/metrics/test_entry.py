"""The console scripts' one runner: a known error is its one line and exit 2, Ctrl-C exit 130
(with what the command says it kept), anything else keeps its traceback."""

from __future__ import annotations

import pytest

from pic4rl_base.entry import Interrupted, entry_point
from pic4rl_base.errors import ConfigError


class OwnError(Exception):
    """A package's own error class (the bridge's ``BridgeError``, say)."""


def _command(error: BaseException | None):  # noqa: ANN202
    @entry_point("pic4rl-x", OwnError, interrupted="interrupted; bags kept")
    def main(argv: list[str] | None = None) -> int:
        """The command's own docstring survives."""
        if error is not None:
            raise error
        return 1
    return main


@pytest.mark.bad_input
@pytest.mark.parametrize("error", [ConfigError("--workers 0: expected a positive number"),
                                   OwnError("--workers 0: expected a positive number")])
def test_a_known_error_is_one_line_and_exit_2(error: Exception,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    assert _command(error)([]) == 2
    assert capsys.readouterr().err == "pic4rl-x: --workers 0: expected a positive number\n"


def test_ctrl_c_is_exit_130_with_the_command_s_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert _command(KeyboardInterrupt())([]) == 130
    assert capsys.readouterr().err == "pic4rl-x: interrupted; bags kept\n"
    assert _command(Interrupted("interrupted; the summary is in s/"))([]) == 130
    assert capsys.readouterr().err == "pic4rl-x: interrupted; the summary is in s/\n"


def test_a_clean_run_returns_its_code_and_a_bug_keeps_its_traceback() -> None:
    assert _command(None)([]) == 1
    assert _command(None).__doc__ == "The command's own docstring survives."
    with pytest.raises(ZeroDivisionError):
        _command(ZeroDivisionError("bug"))([])
