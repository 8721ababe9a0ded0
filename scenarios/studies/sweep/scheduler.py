"""The Dask scheduler of ``rigsim sweep --scheduler``: its address checked, then reached within a
deadline, or refused in one sentence.

:func:`check_address` refuses, before any connection, an address that is not ``tcp://HOST:PORT``
(or ``HOST:PORT``, read as tcp) with a port in 1-65535, or ``tls://HOST:PORT`` with Dask's TLS
settings configured. distributed knows more schemes, none of them usable here: ``ucx://`` needs
the distributed-ucxx package, ``inproc://`` reaches only the same process, ``ws://`` and
``wss://`` are the websocket transport of schedulers started with ``--protocol ws``.

:func:`connect` then looks the host name up, asks the scheduler who it is and what workers it
has (:func:`survey`: distributed's ``identity`` call on a connection of its own, no ``Client``)
and only then opens the ``distributed.Client``, each step within a deadline. The survey comes
first because ``distributed.Client`` bounds its connection attempts (``timeout``) but not the
handshake after a peer accepted the connection: a peer that accepts and stays silent holds it
for ever; a peer that is not Dask (a web server, random bytes) makes distributed raise whatever
its decoder meets (``MemoryError`` for a frame length of exabytes, ``struct.error``), and a
``Client`` that failed so is left open by distributed and blocks the interpreter's exit for
twice its timeout when it is collected. Each step runs in a daemon thread (the survey on an
event loop of its own): nothing of a failed or abandoned attempt reaches the caller but a
message, and nothing of it keeps the process alive.
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import re
import socket
import threading
from collections.abc import Callable
from typing import Any

from rigsim.scenarios.core.config import ScenarioError

__all__ = ["CONNECT_TIMEOUT_S", "WORKERS_TIMEOUT_S", "check_address", "survey", "connect"]

#: s for reaching the scheduler and its first answer (connection attempts, handshake, identity).
CONNECT_TIMEOUT_S = 10.0
#: s to wait for a first worker when the scheduler has none.
WORKERS_TIMEOUT_S = 30.0
#: s past distributed's own connection timeout before a step is given up: its own error (with
#: its reason, "Connection refused") comes first when it has one.
_SLACK_S = 1.0
#: s between two questions to a scheduler that has no worker yet.
_POLL_S = 0.2

_FIX = "give the address `dask scheduler` prints when it starts (tcp://HOST:8786 by default)"
_NEEDS_DISTRIBUTED = "--scheduler needs the 'distributed' package; pip install 'dask[distributed]'"
#: Why a scheme distributed knows (or a web address) is not used here.
_UNUSABLE = {
    "ucx": "needs the distributed-ucxx package",
    "inproc": "reaches only a scheduler inside the same process",
    "ws": "is Dask's websocket transport",
    "wss": "is Dask's websocket transport",
    "http": "is a web address (port 8787 is the scheduler's dashboard)",
    "https": "is a web address (port 8787 is the scheduler's dashboard)",
}
_HOST_PORT = re.compile(r"(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9](?:[A-Za-z0-9._-]*[A-Za-z0-9])?):(?P<port>[0-9]{1,6})")


def _show(address: str) -> str:
    """``address`` as the messages show it: as given, or quoted if it is empty, has blanks or
    characters that do not print (the message stays one visible line)."""
    return address if address and address.isprintable() and not any(c.isspace() for c in address) \
        else repr(address)


def check_address(address: str) -> str:
    """The scheduler address of ``--scheduler``, checked and written ``SCHEME://HOST:PORT``.

    Parameters
    ----------
    address : str
        ``tcp://HOST:PORT``, ``HOST:PORT`` (tcp) or ``tls://HOST:PORT``; HOST a name, an IPv4
        address or a bracketed IPv6 address.

    Returns
    -------
    str
        The address with its scheme (``tcp://`` if none was given).

    Raises
    ------
    ScenarioError
        One sentence naming ``--scheduler``, the address and the fix: a scheme that is not tcp or
        tls, tls without Dask's TLS settings, an address that is not HOST:PORT, a port outside
        1-65535.
    """
    shown = _show(address)
    scheme, sep, rest = address.partition("://")
    if not sep:
        scheme, rest = "tcp", address
    scheme = scheme.lower()
    if scheme not in ("tcp", "tls"):
        what = f"{scheme}://" if scheme.isprintable() and scheme.strip() == scheme and scheme else "its scheme"
        raise ScenarioError(f"--scheduler {shown}: {what} {_UNUSABLE.get(scheme, 'is not a Dask transport')} and "
                            f"rigsim connects over tcp:// (tls:// with Dask's TLS settings), so {_FIX}")
    match = _HOST_PORT.fullmatch(rest)
    if match is None:
        raise ScenarioError(f"--scheduler {shown} is not an address of the form {scheme}://HOST:PORT; {_FIX}")
    port = int(match["port"])
    if not 1 <= port <= 65535:
        raise ScenarioError(f"--scheduler {shown}: port {port} is outside 1-65535; {_FIX}")
    if scheme == "tls":
        _security(f"{scheme}://{rest}")  # refused now if Dask's TLS settings are missing
    return f"{scheme}://{match['host']}:{port}"


def _security(address: str):
    """distributed's ``Security`` from Dask's configuration, the one the survey and the client use.

    Raises
    ------
    ScenarioError
        For a ``tls://`` address, if the configuration gives no TLS client context or it cannot
        be built (a certificate file missing or unreadable).
    """
    try:
        from distributed.security import Security
    except ImportError:
        raise ScenarioError(_NEEDS_DISTRIBUTED) from None
    try:
        security = Security()
        context = security.get_connection_args("client").get("ssl_context")
    except Exception as exc:  # noqa: BLE001 - any failure to build the TLS context is the settings' fault
        reason = " ".join(f"{type(exc).__name__}: {exc}".split())
        raise ScenarioError(f"--scheduler {address}: Dask's TLS settings cannot be used ({reason}); mend them "
                            "(distributed.comm.tls in Dask's configuration) or give a tcp:// address") from None
    if address.startswith("tls://") and context is None:
        raise ScenarioError(f"--scheduler {address}: tls:// needs Dask's TLS settings (distributed.comm.tls.ca-file, "
                            "client.cert and client.key in Dask's configuration) and none are set; set them or "
                            "give the scheduler's tcp:// address")
    return security


class _Refused(Exception):
    """What the scheduler answered makes it unusable (a worker's address, no workers): the message."""


class _Attempt:
    """``fn()`` run in a daemon thread and waited for at most a deadline.

    ``fn`` returns ``(value, None)`` or ``(None, message)`` and never raises: exception objects of
    distributed stay in that thread (their tracebacks hold its connections and clients). If the
    caller stops waiting (deadline, Ctrl-C), a value that arrives later is given to ``late``.
    """

    def __init__(self, fn: Callable[[], tuple[Any, str | None]], name: str,
                 late: Callable[[Any], None] | None = None):
        self._fn, self._late = fn, late
        self._done, self._lock = threading.Event(), threading.Lock()
        self._abandoned, self._outcome = False, (None, None)
        threading.Thread(target=self._run, name=name, daemon=True).start()

    def _run(self) -> None:
        outcome = self._fn()
        with self._lock:
            late = self._abandoned
            self._outcome = (None, None) if late else outcome
            self._done.set()
        if late and outcome[0] is not None and self._late is not None:
            self._late(outcome[0])

    def wait(self, timeout_s: float) -> tuple[Any, str | None] | None:
        """``(value, message)``, or None if ``fn`` has not returned within ``timeout_s``."""
        try:
            finished = self._done.wait(timeout_s)
        finally:
            with self._lock:
                if not self._done.is_set():
                    self._abandoned = True
        return self._outcome if finished else None


def _root(exc: BaseException) -> BaseException:
    """The last of ``exc``'s chain of causes."""
    while exc.__cause__ is not None:
        exc = exc.__cause__
    return exc


def _reason(exc: BaseException) -> str:
    """The root cause of a failed connection, one line ("Connection refused")."""
    exc = _root(exc)
    if getattr(exc, "strerror", None):
        return exc.strerror
    if isinstance(exc, TimeoutError):
        return "every attempt timed out"
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _connect_reason(exc: BaseException, address: str) -> str:
    """Why connecting failed: the system's reason of distributed's last attempt, or, where that
    attempt was cut off by the deadline (its cause then a cancellation), of one plain TCP connect
    to the address, made now within a second ("Connection refused")."""
    if getattr(_root(exc), "strerror", None):
        return _reason(exc)
    host, _, port = address.partition("://")[2].rpartition(":")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=1.0).close()
    except OSError as probe:
        if getattr(probe, "strerror", None):
            return probe.strerror
    except ValueError:
        pass
    return _reason(exc)


def _message(exc: BaseException, address: str, timeout_s: float) -> str:
    """One sentence for any failure of reaching or questioning the scheduler."""
    from distributed.comm import CommClosedError

    if isinstance(exc, _Refused):
        return str(exc)
    if isinstance(exc, TimeoutError):  # a deadline of the survey (asyncio.wait_for)
        return (f"--scheduler {address}: nothing answered there as a Dask scheduler within {timeout_s:g} s; "
                f"check that a scheduler runs there and {_FIX}")
    if isinstance(exc, OSError) and not isinstance(exc, CommClosedError):  # distributed gave up connecting
        return (f"--scheduler {address}: cannot connect within {timeout_s:g} s ({_connect_reason(exc, address)}); "
                f"start a Dask scheduler there or {_FIX}")
    return (f"--scheduler {address}: the peer there does not answer as a Dask scheduler "
            f"({type(exc).__name__} reading its reply); {_FIX}")


async def _identity(comm, timeout_s: float) -> dict:
    """The scheduler's answer to ``identity`` on ``comm`` (its type, workers and their threads)."""
    async def ask():
        await comm.write({"op": "identity", "reply": True})  # a scheduler's and a worker's alike
        return await comm.read()

    info = await asyncio.wait_for(ask(), timeout_s)
    if not isinstance(info, dict) or not isinstance(info.get("type"), str) \
            or not isinstance(info.get("workers", {}), dict):
        raise ValueError(f"an answer that is not an identity: {type(info).__name__}")
    return info


def _resolve(address: str, timeout_s: float) -> None:
    """Look the host name of ``address`` up within ``timeout_s`` (a numeric address needs none).

    distributed resolves names in its event loop's executor, whose threads the interpreter
    joins at exit: a lookup that hangs (a DNS server that does not answer) would hold the
    process after its error. This lookup runs in a daemon thread, and a name that does not
    resolve is said so at once (distributed retries it until its timeout).

    Raises
    ------
    ScenarioError
        The name does not resolve, or not within ``timeout_s``.
    """
    host, _, port = address.partition("://")[2].rpartition(":")
    host = host.strip("[]")
    with contextlib.suppress(ValueError):
        ipaddress.ip_address(host)
        return
    fix = "check the name or give the scheduler's IP address"

    def attempt() -> tuple[Any, str | None]:
        try:
            return socket.getaddrinfo(host, int(port), type=socket.SOCK_STREAM), None
        except Exception as exc:  # noqa: BLE001 - gaierror, or a name the IDNA codec refuses
            return None, f"--scheduler {address}: the host name {host} does not resolve ({_reason(exc)}); {fix}"

    outcome = _Attempt(attempt, "rigsim-dask-resolve").wait(timeout_s)
    if outcome is None:
        raise ScenarioError(f"--scheduler {address}: the host name {host} did not resolve within {timeout_s:g} s; {fix}")
    if outcome[1] is not None:
        raise ScenarioError(outcome[1])


async def _survey(address: str, connection_args: dict, timeout_s: float, workers_timeout_s: float) -> dict[str, int]:
    """:func:`survey`'s questions, each within its deadline, on one connection closed at the end."""
    from distributed.comm import connect as comm_connect

    comm = await asyncio.wait_for(comm_connect(address, timeout=timeout_s, **connection_args),
                                  timeout_s + _SLACK_S)
    try:
        info = await _identity(comm, timeout_s)
        if info["type"] != "Scheduler":
            what = "a Dask worker" if info["type"] == "Worker" else f"a Dask {info['type']}"
            raise _Refused(f"--scheduler {address} is the address of {what}, not of a scheduler; give the "
                           "scheduler's (the address its workers were started with)")
        loop = asyncio.get_running_loop()
        give_up = loop.time() + workers_timeout_s
        while not any(w.get("status") == "running" for w in info.get("workers", {}).values()):
            if loop.time() > give_up:
                raise _Refused(f"--scheduler {address}: the Dask scheduler there has no workers (waited "
                               f"{workers_timeout_s:g} s); start some with dask worker {address} --nthreads 1")
            await asyncio.sleep(_POLL_S)
            info = await _identity(comm, timeout_s)
        return {w: int(ws.get("nthreads", 0)) for w, ws in info["workers"].items()}
    finally:
        try:
            await asyncio.wait_for(comm.write({"op": "close", "reply": False}), 1.0)
            await asyncio.wait_for(comm.close(), 1.0)
        except Exception:  # noqa: BLE001 - a peer that will not say goodbye: drop the connection
            comm.abort()


def survey(address: str, *, timeout_s: float = CONNECT_TIMEOUT_S,
           workers_timeout_s: float = WORKERS_TIMEOUT_S) -> dict[str, int]:
    """The workers of the Dask scheduler at ``address`` and their threads, within a deadline.

    Waits up to ``workers_timeout_s`` for a first running worker if there is none.

    Parameters
    ----------
    address : str
        As :func:`check_address` returns it.
    timeout_s : float, s
        For connecting (distributed retries until then) and for each answer.
    workers_timeout_s : float, s
        For a first worker.

    Returns
    -------
    dict of str to int
        Worker address -> threads.

    Raises
    ------
    ScenarioError
        One sentence naming ``--scheduler`` and the address: its host name does not resolve, it
        cannot be reached, nothing answers within ``timeout_s`` (a peer that accepts and stays
        silent), the peer does not speak Dask's protocol (a web server, random bytes), it is not
        a scheduler, or it has no worker within ``workers_timeout_s``. Never later than
        ``2 * timeout_s + workers_timeout_s`` plus a few seconds.
    """
    connection_args = _security(address).get_connection_args("client")
    _resolve(address, timeout_s)

    def attempt() -> tuple[Any, str | None]:
        try:
            return asyncio.run(_survey(address, connection_args, timeout_s, workers_timeout_s)), None
        except Exception as exc:  # noqa: BLE001 - whatever distributed raises, the user gets one sentence
            return None, _message(exc, address, timeout_s)

    outcome = _Attempt(attempt, "rigsim-dask-survey").wait(timeout_s + workers_timeout_s + 2 * _SLACK_S)
    if outcome is None:
        raise ScenarioError(_message(TimeoutError(), address, timeout_s))
    nthreads, message = outcome
    if message is not None:
        raise ScenarioError(message)
    return nthreads


def connect(address: str, *, timeout_s: float = CONNECT_TIMEOUT_S, workers_timeout_s: float = WORKERS_TIMEOUT_S):
    """A ``distributed.Client`` of the Dask scheduler at ``address``, whose workers run one thread each.

    The address is checked (:func:`check_address`), the scheduler questioned (:func:`survey`),
    then the client opened, each within its deadline.

    Returns
    -------
    distributed.Client

    Raises
    ------
    ScenarioError
        One sentence: distributed is not installed, the address is refused, the scheduler cannot
        be reached or does not answer (:func:`survey`), or a worker runs more than one thread
        (MuJoCo's callbacks are process-global).
    """
    try:
        import distributed
    except ImportError:
        raise ScenarioError(_NEEDS_DISTRIBUTED) from None
    address = check_address(address)
    threaded = {w: n for w, n in survey(address, timeout_s=timeout_s, workers_timeout_s=workers_timeout_s).items()
                if n != 1}
    if threaded:
        w, n = next(iter(threaded.items()))
        raise ScenarioError(
            f"--scheduler {address}: Dask worker {w} runs {n} threads; MuJoCo's callbacks are process-global, "
            f"so start the workers with one thread each (dask worker {address} --nthreads 1 --nworkers N)")
    security = _security(address)

    def attempt() -> tuple[Any, str | None]:
        try:
            return distributed.Client(address, timeout=timeout_s, set_as_default=False, security=security), None
        except Exception as exc:  # noqa: BLE001 - whatever distributed raises, the user gets one sentence
            return None, _message(exc, address, timeout_s)

    outcome = _Attempt(attempt, "rigsim-dask-client", late=_close_quietly).wait(timeout_s + 2 * _SLACK_S)
    if outcome is None:
        raise ScenarioError(_message(TimeoutError(), address, timeout_s))
    client, message = outcome
    if message is not None:
        raise ScenarioError(message)
    return client


def _close_quietly(client) -> None:
    """Close a client nobody waits for any more (its errors have no one to go to)."""
    with contextlib.suppress(Exception):
        client.close(timeout=2 * _SLACK_S)
