"""Network peers that never answer (issue 35, item 7): a ``--scheduler`` that accepts the connection and
says nothing fails within its timeout in one line naming the address, with no ``Client.__del__`` traceback at
exit; an encrypted ``--tls-key`` is refused, never a passphrase prompt."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

pytest.importorskip("distributed")

from isolator import ParameterError
from isolator.sweep.cluster import connect, tls_security

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def silent_peer():
    """A loopback port that accepts connections and never says a word; its address."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(16)
    held: list[socket.socket] = []
    stop = threading.Event()

    def accept() -> None:
        server.settimeout(0.2)
        while not stop.is_set():
            try:
                held.append(server.accept()[0])
            except OSError:
                continue

    thread = threading.Thread(target=accept, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    stop.set()
    thread.join(2)
    for conn in held:
        conn.close()
    server.close()


def test_a_silent_peer_fails_within_the_timeout(silent_peer):
    start = time.monotonic()
    with pytest.raises(ParameterError) as error:
        connect(silent_peer, timeout=2.0)
    took = time.monotonic() - start
    assert took < 2.0 + 3.0, took
    assert str(error.value).startswith(f"scheduler: {silent_peer} accepted the connection but did not answer")


def test_a_silent_peer_is_one_line_from_the_command_and_nothing_is_written(silent_peer, tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "ISOLATOR_QUIET": "1"}
    start = time.monotonic()
    done = subprocess.run([sys.executable, "-m", "isolator.cli", "sweep", "--scale", "isolators[*].damping=1,2",
                           "--scheduler", silent_peer, "--out", "s.csv"], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=60)
    took = time.monotonic() - start
    lines = done.stderr.splitlines()
    assert done.returncode == 2, done.stderr
    assert len(lines) == 1, lines  # no "Exception ignored in Client.__del__" at exit
    assert lines[0].startswith(f"isolator: error: --scheduler: {silent_peer} accepted the connection"), lines
    assert took < 40, took  # the 5 s timeout and the start-up, not 120 s and counting
    assert list(tmp_path.iterdir()) == []


def test_a_refused_scheduler_leaves_no_traceback_at_exit(tmp_path):
    with socket.socket() as probe:  # a port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    env = {**os.environ, "PYTHONPATH": str(ROOT), "ISOLATOR_QUIET": "1"}
    done = subprocess.run([sys.executable, "-m", "isolator.cli", "sweep", "--scale", "isolators[*].damping=1,2",
                           "--scheduler", f"tcp://127.0.0.1:{port}", "--out", "s.csv"], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert done.stderr.splitlines() == [done.stderr.strip()], done.stderr
    assert "cannot reach a Dask scheduler" in done.stderr


@pytest.mark.skipif(shutil.which("openssl") is None, reason="needs the openssl command")
def test_an_encrypted_key_is_refused_without_a_prompt(tmp_path):
    def openssl(*args: str) -> None:
        subprocess.run(["openssl", *args], cwd=tmp_path, check=True, capture_output=True, stdin=subprocess.DEVNULL)

    openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2", "-subj", "/CN=ca", "-keyout", "ca.key",
            "-out", "ca.pem")
    openssl("req", "-x509", "-newkey", "rsa:2048", "-days", "2", "-subj", "/CN=client", "-keyout", "client.key",
            "-out", "client.pem", "-passout", "pass:secret")
    assert "ENCRYPTED" in (tmp_path / "client.key").read_text()
    start = time.monotonic()
    with pytest.raises(ParameterError, match=r"^--tls-key: .*is encrypted"):
        tls_security(tmp_path / "ca.pem", tmp_path / "client.pem", tmp_path / "client.key",
                     {"ca": "--tls-ca-file", "cert": "--tls-cert", "key": "--tls-key", "tls": "--tls"})
    assert time.monotonic() - start < 5


def test_a_cluster_without_workers_says_so(capfd):
    """A scheduler with no workers: the sweep says "0 workers" after 2 s rather than wait in silence."""
    from distributed import LocalCluster

    from isolator.errors import ExecutorError
    from isolator.sweep import sweep

    cluster = LocalCluster(n_workers=0, processes=False, dashboard_address=None)
    failed: list[BaseException] = []

    def run() -> None:
        try:
            sweep("paper-table-3-2", scale={"isolators[*].damping": [1.0, 2.0]}, scheduler=cluster.scheduler_address,
                  progress=True)
        except BaseException as exc:  # the cluster closed under it
            failed.append(exc)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    deadline, seen = time.monotonic() + 30, ""
    while time.monotonic() < deadline and "0 workers" not in seen:
        time.sleep(0.5)
        seen += capfd.readouterr().err
    cluster.close()
    thread.join(30)
    assert "isolator sweep: 0 workers: the chunks wait until a worker joins" in seen, seen
    assert not thread.is_alive()
    assert failed
    assert isinstance(failed[0], ExecutorError | ParameterError), failed
