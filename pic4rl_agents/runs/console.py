"""The command lines' console: what the library logs, shown to the user as the CLI prints."""

from __future__ import annotations

import contextlib
import logging
import sys
from collections.abc import Iterator
from typing import TextIO


class _BarAwareHandler(logging.StreamHandler):  # type: ignore[type-arg]
    """A stream handler that clears tqdm's bars on its stream, writes, and redraws them."""

    def emit(self, record: logging.LogRecord) -> None:
        from tqdm import tqdm

        try:
            tqdm.write(self.format(record), file=self.stream)
        except Exception:  # noqa: BLE001 -- logging's own contract: report, never raise
            self.handleError(record)


@contextlib.contextmanager
def console_logging(logger: str, fmt: str = "%(message)s", *,
                    stream: TextIO | None = None) -> Iterator[None]:
    """While the block runs, ``logger``'s records from INFO up are written to ``stream``
    (``sys.stderr`` as it is then) in ``fmt``, through ``tqdm.write``: a line never cuts
    through a progress bar on that stream."""
    handler = _BarAwareHandler(stream or sys.stderr)
    handler.setFormatter(logging.Formatter(fmt))
    target = logging.getLogger(logger)
    level = target.level
    target.addHandler(handler)
    target.setLevel(logging.INFO)
    try:
        yield
    finally:
        target.removeHandler(handler)
        target.setLevel(level)
