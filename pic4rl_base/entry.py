"""Every console script's one runner (evo's ``entry_points`` habit): what a known error and
Ctrl-C end in is written once, here, not in each command.

``@entry_point("pic4rl-test", BridgeError, interrupted="...")`` over a ``main(argv) -> int``:
a known error (``Pic4rlError``, which ``ConfigError`` and each package's own errors are, and the classes
named) prints ``<prog>: <its one line>`` and exits 2; Ctrl-C prints ``<prog>: <interrupted>``
and exits 130. A command that must say more after Ctrl-C (where it left its summary) cleans up
and raises ``Interrupted("interrupted; ...")``. Anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable
from typing import TypeVar

from .errors import Pic4rlError

#: Exit code of a known error: bad input, named in one line.
EXIT_BAD_INPUT = 2
#: Exit code after Ctrl-C (128 + SIGINT), as a shell reports it.
EXIT_INTERRUPTED = 130

Main = TypeVar("Main", bound=Callable[..., int])


class Interrupted(KeyboardInterrupt):
    """Ctrl-C, with what the command says about it (what was kept, where)."""


def entry_point(prog: str, *known: type[BaseException],
                interrupted: str = "interrupted") -> Callable[[Main], Main]:
    """Decorator of a command's ``main``: known errors → exit 2, Ctrl-C → exit 130."""

    def wrap(main: Main) -> Main:
        @functools.wraps(main)
        def run(*args: object, **kwargs: object) -> int:
            try:
                return main(*args, **kwargs)
            except KeyboardInterrupt as err:
                said = str(err) if isinstance(err, Interrupted) and str(err) else interrupted
                print(f"{prog}: {said}", file=sys.stderr)
                return EXIT_INTERRUPTED
            except (Pic4rlError, *known) as err:
                print(f"{prog}: {err}", file=sys.stderr)
                return EXIT_BAD_INPUT

        return run  # type: ignore[return-value]

    return wrap
