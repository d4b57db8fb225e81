"""Joining Ray for ``pic4rl-bench`` and ``pic4rl-tune`` (``--address``): a wrong or unreachable
address is one line (a ``ConfigError``) within a bounded time, never a traceback or a hang.

``HOST:PORT`` is probed first with a TCP connection (``PROBE_S``): nothing listening there is
said at once. Then ``ray.init`` runs under a deadline (``JOIN_S``), since Ray retries a silent
or foreign port for minutes. A cluster that ``ray start --head`` started asks for token
authentication (Ray 2.5x): a process joining it by ``HOST:PORT`` needs ``RAY_AUTH_MODE=token``
and the cluster's token (``~/.ray/auth_token``, or ``RAY_AUTH_TOKEN``); ``auto`` finds both on
a machine of the cluster. Without an address, Ray is started here, of its own (``local``), even
when a cluster runs on this machine.
"""

from __future__ import annotations

import socket
import threading
from typing import Any

from pic4rl_bridge.errors import ConfigError

PROBE_S = 5.0
JOIN_S = 60.0
_AUTH = ("InvalidAuthToken", "AuthenticationError", "Authentication token")


def _probe(address: str) -> None:
    """``ConfigError`` unless something accepts a TCP connection at ``HOST:PORT``."""
    host, _, port = address.removeprefix("ray://").rpartition(":")
    if not host or not port.isdigit():
        raise ConfigError(f"--address {address}: expected HOST:PORT (a Ray head's port, "
                          "e.g. 10.0.0.1:6379), auto or local")
    try:
        socket.create_connection((host, int(port)), timeout=PROBE_S).close()
    except OSError as err:
        raise ConfigError(f"--address {address}: no Ray cluster there ({err.strerror or err}); "
                          "is `ray start --head` running on that machine and port?") from None


def _reason(err: BaseException) -> str:
    """Why joining failed, in one line; the token hint when the cluster wants one."""
    chain, cause = [], err
    while cause is not None:
        chain.append(f"{type(cause).__name__}: {cause}")
        cause = cause.__cause__ or cause.__context__
    text = " ".join(" / ".join(chain).split())
    if any(mark in text for mark in _AUTH):
        return ("the cluster asks for token authentication: run with RAY_AUTH_MODE=token and "
                "its token in ~/.ray/auth_token or RAY_AUTH_TOKEN (docs/bench.md)")
    return text.split(" / ")[0][:300]


def init(address: str | None, **kwargs: Any) -> None:
    """``ray.init`` on the cluster at ``address`` (``auto``, ``HOST:PORT``), or on a Ray of
    its own here (``None`` or ``local``); ``ConfigError`` in one line when that fails."""
    import ray

    if address in (None, "local"):
        ray.init(address="local", **kwargs)
        return
    if address != "auto":
        _probe(address)
    failed: list[BaseException] = []

    def join() -> None:
        try:
            ray.init(address=address, **kwargs)
        except Exception as err:  # noqa: BLE001 - reported in one line by the caller
            failed.append(err)

    thread = threading.Thread(target=join, name="ray-join", daemon=True)
    thread.start()
    thread.join(JOIN_S)
    if thread.is_alive():
        raise ConfigError(f"--address {address}: no Ray cluster answered within {JOIN_S:.0f} "
                          "s; is it a Ray head's port (ray start --head --port)?")
    if failed:
        raise ConfigError(f"--address {address}: {_reason(failed[0])}")
