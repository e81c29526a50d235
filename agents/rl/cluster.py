"""Ray sessions: a local instance by default, an existing cluster by address, clear errors.

``poc-env train --engine rllib`` and ``poc-env evaluate/experiment --ray`` run inside
:func:`ray_session`. Without an address it starts a local Ray instance (``num_cpus``, no
dashboard) and stops it afterwards; with one it joins that cluster and leaves it running:

- ``host:port``: a head node started with ``ray start --head --port=6379`` (the driver runs on a
  cluster node);
- ``ray://host:10001``: the Ray Client port of a head node (the driver runs elsewhere);
- ``auto``: the cluster already running on this machine.

A ``host:port`` or ``ray://`` address is probed first (:func:`probe`): a TCP connection, then
the opening of gRPC's HTTP/2 handshake, which both of Ray's ports (the GCS and the Ray Client
server) answer with a SETTINGS frame. An address where nothing answers, or where a service
that is not Ray listens (a web server, a database, a silent socket), fails within
:data:`PROBE_TIMEOUT_S` seconds with an error naming it, instead of ``ray.init``'s retry loop,
which does not end against a service that accepts connections and never speaks gRPC.
Ray comes with the ``rllib`` extra; without it a
:class:`~poc_env.errors.MissingExtraError` names the extra.
"""

from __future__ import annotations

import contextlib
import os
import socket
from collections.abc import Iterator

from poc_env.errors import ConfigError, MissingExtraError

#: Seconds to wait for a TCP answer from a cluster address before giving up.
PROBE_TIMEOUT_S = 3.0
_ALLOWED = (
    "host:port of a running Ray head node (ray start --head prints it), ray://host:10001 "
    "(Ray Client), auto (the cluster on this machine) or local (a new local instance)"
)


def _host_port(address: str) -> tuple[str, int]:
    text = address.removeprefix("ray://")
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ConfigError("address", address, _ALLOWED)
    return host.strip("[]"), int(port)


#: The client's opening of an HTTP/2 connection (RFC 9113 3.4): the preface, then an empty
#: SETTINGS frame (length 0, type 4, no flags, stream 0).
_H2_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])
_H2_SETTINGS = 4


def _read_frame_header(sock: socket.socket, deadline: float) -> bytes:
    """Up to the 9 bytes of the first HTTP/2 frame header the peer sends (fewer if it closes
    or ``deadline``, a ``time.monotonic()`` value, passes)."""
    import time

    got = b""
    while len(got) < 9:
        left = deadline - time.monotonic()
        if left <= 0:
            break
        sock.settimeout(left)
        try:
            chunk = sock.recv(9 - len(got))
        except TimeoutError:
            break
        if not chunk:
            break
        got += chunk
    return got


def probe(address: str, timeout_s: float = PROBE_TIMEOUT_S) -> None:
    """ConfigError unless a gRPC server (Ray's GCS or Ray Client port) answers at ``address``
    within ``timeout_s`` seconds: it must accept a TCP connection and answer the HTTP/2
    preface with a SETTINGS frame, as every gRPC server does before any call."""
    import time

    host, port = _host_port(address)
    deadline = time.monotonic() + timeout_s
    try:
        with socket.create_connection((host, port), timeout=timeout_s) as sock:
            sock.sendall(_H2_PREFACE)
            head = _read_frame_header(sock, deadline)
    except OSError as exc:
        raise ConfigError(
            "address",
            address,
            f"{_ALLOWED}; nothing answered at {host}:{port} within {timeout_s:g} s ({exc})",
        ) from None
    if len(head) < 9 or head[3] != _H2_SETTINGS:
        what = "did not answer" if not head else f"answered {head[:9]!r}"
        raise ConfigError(
            "address",
            address,
            f"{_ALLOWED}; a service accepts connections at {host}:{port} but it is not Ray: it "
            f"{what} to gRPC's HTTP/2 handshake within {timeout_s:g} s (Ray's GCS and Ray "
            "Client ports speak gRPC)",
        )


def require_ray(what: str):
    """The ``ray`` module, or MissingExtraError naming the ``rllib`` extra."""
    try:
        import ray
    except ModuleNotFoundError as exc:
        if (exc.name or "").partition(".")[0] != "ray":
            raise
        raise MissingExtraError("rllib", what) from exc
    return ray


@contextlib.contextmanager
def ray_session(address: str | None = None, num_cpus: int = 2, what: str = "Ray") -> Iterator:
    """Ray, initialised for the ``with`` block (module docstring); yields the ``ray`` module.

    ``address``: None or ``"local"`` (a new local instance with ``num_cpus`` CPUs, stopped on
    exit), ``"auto"``, ``host:port`` or ``ray://host:port`` (joined, disconnected on exit). If
    Ray is already initialised in this process, that session is used and left alone."""
    if address is not None and (not isinstance(address, str) or not address.strip()):
        raise ConfigError("address", address, _ALLOWED)
    ray = require_ray(what)
    if address not in (None, "local", "auto"):
        assert address is not None
        probe(address)
    if ray.is_initialized():
        yield ray
        return
    # quiet, local-only defaults: no dashboard, no usage reporting
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    kwargs: dict = {"include_dashboard": False, "log_to_driver": False}
    if address in (None, "local"):
        ray.init(num_cpus=num_cpus, **kwargs)
    else:
        try:
            ray.init(address=address, **kwargs)
        except ConnectionError as exc:
            raise ConfigError("address", address, f"{_ALLOWED} ({exc})") from None
    try:
        yield ray
    finally:
        ray.shutdown()
