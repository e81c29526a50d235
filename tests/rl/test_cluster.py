"""The Ray address probe (poc_env.agents.rl.cluster.probe): an address where a TCP service
that is not Ray listens fails within seconds with a clear error, instead of ``ray.init``'s
retry loop (issue 27, hangs). Local servers on 127.0.0.1 only; the gRPC stage's tests need
grpcio and Ray's generated messages (the rllib extra)."""

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


def _needs_ray_grpc():
    pytest.importorskip("grpc", reason="the rllib extra is not installed")
    pytest.importorskip("ray.core.generated.gcs_service_pb2", reason="no rllib extra")


def test_a_bare_http2_answer_is_not_enough():
    """Issue 27: a server that answers the HTTP/2 preface with a SETTINGS frame (any gRPC or
    HTTP/2 server) passed the probe, and ``ray.init`` then retried for minutes. The probe now
    also calls Ray's API."""
    _needs_ray_grpc()
    settings = bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])
    with tcp_server(settings) as address, pytest.raises(ConfigError, match="not Ray") as err:
        cluster.probe(address, timeout_s=1.0)
    assert "did not answer Ray's /ray.rpc.NodeInfoGcsService/GetClusterId call" in str(err.value)


@contextlib.contextmanager
def grpc_server(*servicers):
    """A gRPC server on a free 127.0.0.1 port with the given (add_to_server, servicer) pairs
    (none: a gRPC server of no service Ray knows); yields its ``host:port``."""
    from concurrent import futures

    import grpc

    srv = grpc.server(futures.ThreadPoolExecutor(2))
    for add, servicer in servicers:
        add(servicer, srv)
    port = srv.add_insecure_port("127.0.0.1:0")
    srv.start()
    try:
        yield f"127.0.0.1:{port}"
    finally:
        srv.stop(0)


def test_a_grpc_service_that_is_not_ray_is_refused():
    _needs_ray_grpc()
    with grpc_server() as address:
        for spelling in (address, "ray://" + address):
            with pytest.raises(ConfigError, match="UNIMPLEMENTED") as err:
                cluster.probe(spelling, timeout_s=2.0, field="ray")
            assert err.value.field == "ray" and err.value.value == spelling
            assert "not Ray" in str(err.value) and "ray://host:10001" in err.value.allowed


def test_a_server_answering_rays_api_passes():
    """What passes: Ray's GCS call answered with a cluster id (a real GCS passes in
    tests/rl/test_rllib.py) or refused as Ray refuses a call without its token (Ray 2.60 turns
    token authentication on by default) and, with ray://, the Ray Client server's ping; a GCS
    answer without a cluster id, or another service's UNAUTHENTICATED, does not."""
    _needs_ray_grpc()
    import grpc
    from ray.core.generated import (
        gcs_service_pb2,
        gcs_service_pb2_grpc,
        ray_client_pb2,
        ray_client_pb2_grpc,
    )

    class Gcs(gcs_service_pb2_grpc.NodeInfoGcsServiceServicer):
        def __init__(self, cluster_id: bytes):
            self.cluster_id = cluster_id

        def GetClusterId(self, request, context):
            if self.cluster_id.startswith(b"refuse:"):
                context.abort(grpc.StatusCode.UNAUTHENTICATED, self.cluster_id[7:].decode())
            return gcs_service_pb2.GetClusterIdReply(cluster_id=self.cluster_id)

    class Client(ray_client_pb2_grpc.RayletDriverServicer):
        def ClusterInfo(self, request, context):
            return ray_client_pb2.ClusterInfoResponse(json="{}")

    add_gcs = gcs_service_pb2_grpc.add_NodeInfoGcsServiceServicer_to_server
    add_client = ray_client_pb2_grpc.add_RayletDriverServicer_to_server
    with grpc_server((add_gcs, Gcs(b"\x01" * 28)), (add_client, Client())) as address:
        cluster.probe(address, timeout_s=5.0)
        cluster.probe("ray://" + address, timeout_s=5.0)
    ray_refusal = b"refuse:InvalidAuthToken: Authentication token is missing or incorrect"
    with grpc_server((add_gcs, Gcs(ray_refusal))) as address:
        cluster.probe(address, timeout_s=5.0)
    for reply, said in [(b"", "without a cluster id"), (b"refuse:who are you", "UNAUTHENTICATED")]:
        with (
            grpc_server((add_gcs, Gcs(reply))) as address,
            pytest.raises(ConfigError, match=said),
        ):
            cluster.probe(address, timeout_s=5.0)


def test_the_cli_names_the_address(capsys):
    pytest.importorskip("ray", reason="the rllib extra is not installed")
    from poc_env.cli import main

    with tcp_server(None) as address:
        t0 = time.perf_counter()
        argv = ["evaluate", "--scenario", "small", "--episodes", "1", "--ray", address]
        assert main(argv) == 2
        assert time.perf_counter() - t0 < 30
    err = capsys.readouterr().err
    assert f"ray: got '{address}'" in err and "not Ray" in err  # the option evaluate takes


@pytest.mark.parametrize("command", ["evaluate", "train"])
def test_a_command_given_a_grpc_service_that_is_not_ray_returns(tmp_path, command):
    """Issue 27: ``evaluate --ray`` / ``train --address`` at a gRPC service that is not Ray
    (it passed the handshake) ended in ray.init's retries. In a subprocess (a generous
    timeout, no timed assertion): exit 2, an error naming the option and the address, and no
    run folder written."""
    import subprocess
    import sys

    _needs_ray_grpc()
    run = tmp_path / "run"
    with grpc_server() as address:
        if command == "evaluate":
            argv, field = ["evaluate", "--scenario", "small", "--episodes", "1", "--ray"], "ray"
        else:
            argv = ["train", "--engine", "rllib", "--task", "UAVSearch-Small-Random-Heading-v0",
                    "--total-timesteps", "100", "--run-dir", str(run), "--address"]  # fmt: skip
            field = "address"
        proc = subprocess.run(
            [sys.executable, "-m", "poc_env.cli", *argv, address],
            capture_output=True,
            text=True,
            timeout=600,
            cwd=tmp_path,
        )
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert f"{field}: got '{address}'" in proc.stderr and "not Ray" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert not run.exists()
