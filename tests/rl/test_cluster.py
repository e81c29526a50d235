"""The Ray address probe (poc_env.agents.rl.cluster.probe): an address where a TCP service
that is not Ray listens fails within seconds with a clear error, instead of ``ray.init``'s
retry loop (issue 27, hangs). Local servers on 127.0.0.1 only; Ray is not needed."""

from __future__ import annotations

import contextlib
import socket
import threading
import time

import pytest

from poc_env.agents.rl import cluster
from poc_env.errors import ConfigError


@contextlib.contextmanager
def tcp_server(reply: bytes | None):
    """A TCP server on a free 127.0.0.1 port that answers each connection with ``reply``
    (None: reads and never answers); yields its ``host:port``."""
    srv = socket.create_server(("127.0.0.1", 0))
    srv.settimeout(0.2)
    stop = threading.Event()
    conns: list[socket.socket] = []

    def serve():
        while not stop.is_set():
            try:
                conn, _ = srv.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            conns.append(conn)
            if reply is not None:
                with contextlib.suppress(OSError):
                    conn.sendall(reply)

    t = threading.Thread(target=serve, daemon=True)
    t.start()
    try:
        yield f"127.0.0.1:{srv.getsockname()[1]}"
    finally:
        stop.set()
        t.join(2)
        srv.close()
        for c in conns:
            c.close()


@pytest.mark.parametrize(
    ("reply", "said"),
    [
        (None, "did not answer"),  # a silent service: ray.init waited for ever
        (b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n", "answered b'HTTP/1.1 '"),
        (b"", "did not answer"),  # accepts, then closes at once
    ],
)
def test_a_service_that_is_not_ray_fails_within_seconds(reply, said):
    with tcp_server(reply) as address:
        t0 = time.perf_counter()
        with pytest.raises(ConfigError, match="it is not Ray") as err:
            cluster.probe(address, timeout_s=1.0)
        assert time.perf_counter() - t0 < 5
    assert err.value.field == "address" and err.value.value == address
    assert said in str(err.value)
    with tcp_server(reply) as address, pytest.raises(ConfigError, match="not Ray"):
        cluster.probe("ray://" + address, timeout_s=1.0)  # the Ray Client spelling too


def test_a_grpc_like_answer_passes():
    """The probe asks what every gRPC server answers (an HTTP/2 SETTINGS frame first)."""
    settings = bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])
    with tcp_server(settings) as address:
        cluster.probe(address, timeout_s=2.0)


def test_the_cli_names_the_address(capsys):
    pytest.importorskip("ray", reason="the rllib extra is not installed")
    from poc_env.cli import main

    with tcp_server(None) as address:
        t0 = time.perf_counter()
        argv = ["evaluate", "--scenario", "small", "--episodes", "1", "--ray", address]
        assert main(argv) == 2
        assert time.perf_counter() - t0 < 30
    err = capsys.readouterr().err
    assert f"address: got '{address}'" in err and "not Ray" in err
