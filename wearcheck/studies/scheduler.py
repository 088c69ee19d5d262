"""Reaching an existing Dask scheduler (``--scheduler ADDRESS``), within a deadline.

``distributed`` waits without limit for a peer's handshake: an address where
something accepts connections but does not speak Dask (a dashboard, a
database), a scheduler stopped with SIGSTOP, would hang the study for ever;
a server that greets first (SSH, SMTP) has its greeting read as a message
length and fails as "out of memory". Here the address is checked first (its
scheme, port, and for ``tls://`` the certificates; exit 2), then one
connection exchanges Dask's handshake and asks the peer who it is, all within
:func:`answer_timeout` seconds, in a thread of its own (exit 1, one line,
for every way that fails). :func:`nthreads` bounds the study's later requests
the same way.
"""

from __future__ import annotations

import asyncio
import os
import socket
import threading

from wearcheck import cases

#: seconds a scheduler may take to answer (its handshake, a request); the
#: environment variable WEARCHECK_WORKER_TIMEOUT lowers it when set lower
ANSWER_TIMEOUT = 10.0


class SchedulerError(cases.WearcheckError):
    """The Dask scheduler cannot be used: unreachable, silent, or not a scheduler (exit 1)."""


def answer_timeout(worker_timeout: float) -> float:
    return min(ANSWER_TIMEOUT, worker_timeout)


def check_address(address: str) -> dict:
    """Refuse (CaseError, exit 2) an address this machine cannot use; return the
    connection arguments (TLS context) for it."""
    from distributed.comm import parse_address
    from distributed.comm.registry import get_backend
    from distributed.comm.addressing import parse_host_port
    try:
        scheme, location = parse_address(address)
    except ValueError as exc:
        raise cases.CaseError(f"--scheduler '{address}': {exc}") from None
    if scheme == "inproc":
        raise cases.CaseError(f"--scheduler '{address}': an inproc:// scheduler lives inside "
                              "another Python process and cannot be reached from here; give "
                              "its tcp:// address")
    try:
        backend = get_backend(scheme)
        backend.get_connector()
    except ValueError as exc:
        raise cases.CaseError(f"--scheduler '{address}': {exc}") from None
    except Exception as exc:  # noqa: BLE001 - e.g. UCX's abstract connector without ucxx
        raise cases.CaseError(f"--scheduler '{address}': this installation cannot connect "
                              f"by {scheme}:// ({type(exc).__name__}: {exc}); use tcp://"
                              + (" or install distributed-ucxx" if scheme == "ucx" else ""))
    if scheme in ("tcp", "tls", "ws", "wss"):
        try:
            host, port = parse_host_port(location)
        except ValueError as exc:
            raise cases.CaseError(f"--scheduler '{address}': {exc}; e.g. "
                                  f"{scheme}://127.0.0.1:8786") from None
        if not 0 < int(port) < 65536:
            raise cases.CaseError(f"--scheduler '{address}': port {port} is not a TCP port "
                                  "(1 to 65535)")
    from distributed.security import Security
    try:
        args = Security().get_connection_args("client")
    except Exception as exc:  # noqa: BLE001 - unreadable certificate files in the config
        raise cases.CaseError(f"--scheduler '{address}': Dask's TLS configuration cannot be "
                              f"used ({type(exc).__name__}: {exc})") from None
    if scheme in ("tls", "wss") and args.get("ssl_context") is None:
        raise cases.CaseError(f"--scheduler '{address}': {scheme}:// needs certificates, and "
                              "Dask's configuration names none (distributed.comm.tls.ca-file, "
                              "distributed.comm.tls.client.cert and .key); set them, or use "
                              "tcp://")
    return args


def _in_thread(coroutine_function, timeout: float):
    """Run ``coroutine_function()`` on an event loop of its own, in a thread, for at most
    ``timeout`` s (a caller may itself run inside an event loop, as Jupyter does).
    Returns its result; raises what it raised, or TimeoutError."""
    box = {}

    def target():
        try:
            box["value"] = asyncio.run(asyncio.wait_for(coroutine_function(), timeout))
        except BaseException as exc:  # noqa: BLE001 - handed to the caller
            box["error"] = exc
    thread = threading.Thread(target=target, daemon=True, name="wearcheck-scheduler-probe")
    thread.start()
    thread.join(timeout + 5.0)
    if thread.is_alive():
        raise TimeoutError("the probe did not return")
    if "error" in box:
        raise box["error"]
    return box["value"]


def _greeting(address: str) -> str:
    """The first bytes a TCP server at ``address`` sends unasked (its banner), printable."""
    from distributed.comm import parse_address
    from distributed.comm.addressing import parse_host_port
    try:
        host, port = parse_host_port(parse_address(address)[1])
        with socket.create_connection((host, port), timeout=2.0) as sock:
            sock.settimeout(2.0)
            data = sock.recv(64)
    except (OSError, ValueError):
        return ""
    text = data.decode("latin-1").split("\n")[0].strip()
    return "".join(ch if ch.isprintable() else "?" for ch in text)[:40]


def _reach(address: str, timeout: float) -> None:
    """A TCP connection to the address's host and port, first: what fails there (an unknown
    host, a refused or unanswered connection) is told apart from a peer that is no
    scheduler."""
    from distributed.comm import parse_address
    from distributed.comm.addressing import parse_host_port
    scheme, location = parse_address(address)
    if scheme not in ("tcp", "tls", "ws", "wss"):
        return
    host, port = parse_host_port(location)
    where = f"the Dask scheduler at '{address}'"
    try:
        socket.create_connection((host, port), timeout=timeout).close()
    except socket.gaierror as exc:
        raise SchedulerError(f"cannot reach {where}: its host name is not known "
                             f"({exc.strerror or exc})") from None
    except ConnectionRefusedError:
        raise SchedulerError(f"cannot reach {where}: the connection was refused (nothing "
                             "listens there); is the scheduler running, and the port "
                             "right?") from None
    except (TimeoutError, socket.timeout):
        raise SchedulerError(f"cannot reach {where}: no connection within {timeout:g} s "
                             "(a firewall, or no such machine?)") from None
    except OSError as exc:
        raise SchedulerError(f"cannot reach {where}: {exc.strerror or exc}") from None


def probe(address: str, timeout: float, connection_args: dict) -> dict:
    """Connect to ``address``, exchange Dask's handshake and ask the peer who it is,
    within ``timeout`` s. Returns its identity; SchedulerError naming what failed."""
    from distributed.comm import connect

    async def identity():
        comm = await connect(address, timeout=timeout, **connection_args)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    where = f"the Dask scheduler at '{address}'"
    _reach(address, timeout)
    try:
        answer = _in_thread(identity, timeout)
    except (TimeoutError, asyncio.TimeoutError):
        raise SchedulerError(f"{where} accepted the connection but did not answer within "
                             f"{timeout:g} s: it may be stopped (SIGSTOP), overloaded, or not "
                             "a Dask scheduler (a dashboard's port?)") from None
    except OSError as exc:
        text = f"nothing answered within {timeout:g} s" if "Timed out" in str(exc) else \
            str(exc)[:200]
        raise SchedulerError(f"cannot reach {where}: {text}") from None
    except (MemoryError, ValueError, TypeError, KeyError, EOFError, AssertionError) as exc:
        sent = _greeting(address)
        said = f"it sent '{sent}'" if sent else f"its answer is not Dask's ({type(exc).__name__})"
        raise SchedulerError(f"'{address}' is not a Dask scheduler: {said}") from None
    except Exception as exc:  # noqa: BLE001 - a closed comm, a protocol error
        raise SchedulerError(f"cannot talk to {where}: {type(exc).__name__}: "
                             f"{str(exc)[:200]}") from None
    if not isinstance(answer, dict) or "type" not in answer:
        raise SchedulerError(f"'{address}' is not a Dask scheduler: it answered Dask's "
                             f"handshake but not its identity request")
    if answer.get("type") != "Scheduler":
        kind = answer.get("type")
        raise SchedulerError(f"'{address}' is a Dask {kind}, not the scheduler: give the "
                             "scheduler's address (the one its workers were started with)")
    return answer


def client(address: str, timeout: float, connection_args: dict):
    """A ``distributed.Client`` on the scheduler at ``address`` (probed first), made
    within ``timeout`` s: a scheduler that stops answering in between is a SchedulerError."""
    from distributed import Client
    probe(address, timeout, connection_args)
    box = {}

    def target():
        try:
            box["client"] = Client(address, timeout=f"{timeout}s")
        except BaseException as exc:  # noqa: BLE001 - handed to the caller
            box["error"] = exc
    thread = threading.Thread(target=target, daemon=True, name="wearcheck-scheduler-client")
    thread.start()
    thread.join(timeout + 5.0)
    if thread.is_alive():
        raise SchedulerError(f"the Dask scheduler at '{address}' stopped answering while the "
                             f"client connected (more than {timeout:g} s)")
    if "error" in box:
        exc = box["error"]
        raise SchedulerError(f"cannot connect to the Dask scheduler at '{address}': "
                             f"{type(exc).__name__}: {str(exc)[:200]}") from None
    return box["client"]


def nthreads(client_, timeout: float) -> dict:
    """{worker: threads} of the client's scheduler; TimeoutError (or OSError, when it
    is gone) if it does not answer within ``timeout`` s."""
    return client_.nthreads(callback_timeout=timeout)


def wait_for_worker(client_, address: str, worker_timeout: float, timeout: float) -> None:
    """Return once the scheduler has a worker; SchedulerError when none joined within
    ``worker_timeout`` s, or the scheduler stopped answering (each request ``timeout`` s).

    (``Client.wait_for_workers`` would wait for ever on a scheduler stopped meanwhile.)
    """
    import time
    start = time.monotonic()
    while True:
        try:
            if nthreads(client_, timeout):
                return
        except Exception:  # noqa: BLE001 - no answer in time, or the scheduler is gone
            raise SchedulerError(f"the Dask scheduler at '{address}' stopped answering (no "
                                 f"reply within {timeout:g} s)") from None
        if time.monotonic() - start >= worker_timeout:
            raise SchedulerError(f"the Dask scheduler at '{address}' has no worker: none "
                                 f"joined within {worker_timeout:g} s; start workers (dask "
                                 f"worker {address}) or drop --scheduler")
        time.sleep(0.1)


def quiet_logs():
    """Silence distributed's own log lines (e.g. "Failed to reconnect to scheduler")
    while a study talks to an external scheduler, whose failures it reports itself
    in one line; returns the function that restores them."""
    import logging
    loggers = [logging.getLogger(n) for n in ("distributed", "distributed.client",
                                               "distributed.core", "distributed.comm")]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.CRITICAL + 1)

    def restore():
        for lg, level in zip(loggers, levels):
            lg.setLevel(level)
    return restore


def environment_timeout(name: str, default: float) -> float:
    """A positive number of seconds from the environment variable ``name``, else ``default``."""
    try:
        value = float(os.environ.get(name, default))
    except ValueError:
        return default
    return value if value > 0 else default
