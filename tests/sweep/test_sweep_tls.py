"""Sweeps on a Dask cluster that lets no one in: a real TLS ``LocalCluster`` (a CA and certificates made here
with ``openssl``) runs the local rows; every bad certificate is one line naming the option, exit status 2,
nothing written; a plain tcp:// scheduler beyond loopback runs, with one warning."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
from pathlib import Path

import pytest

from conftest import run_command as run
from isolator.cli.app import main
from isolator.errors import ParameterError
from isolator.sweep import sweep
from isolator.sweep.cluster import is_loopback, tls_security

distributed = pytest.importorskip("distributed")
pytestmark = pytest.mark.skipif(shutil.which("openssl") is None, reason="needs the openssl command")

SCALE = ["--scale", "isolators[*].stiffness=0.6,1.0,1.7", "--scale", "isolators[*].damping=0.5,2.0"]
GRID = {"isolators[*].stiffness": [0.6, 1.0, 1.7], "isolators[*].damping": [0.5, 2.0]}


def openssl(*args: str, cwd: Path) -> None:
    subprocess.run(["openssl", *args], cwd=cwd, check=True, capture_output=True)


def make_ca(folder: Path, name: str) -> None:
    """A CA (``<name>-ca.pem``) and one certificate it signed (``<name>.pem``, key ``<name>-key.pem``), as
    the user guide's recipe (docs/guide/sweeps.md) makes them."""
    openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2", "-subj", f"/CN={name}-ca",
            "-keyout", f"{name}-ca-key.pem", "-out", f"{name}-ca.pem", cwd=folder)
    openssl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2", "-subj", f"/CN={name}",
            "-addext", "basicConstraints=critical,CA:FALSE", "-CA", f"{name}-ca.pem", "-CAkey",
            f"{name}-ca-key.pem", "-keyout", f"{name}-key.pem", "-out", f"{name}.pem", cwd=folder)


@pytest.fixture(scope="module")
def certs(tmp_path_factory) -> Path:
    """``cluster`` (the scheduler's, workers' and clients') and ``intruder`` (another CA's) certificates."""
    folder = tmp_path_factory.mktemp("certs")
    make_ca(folder, "cluster")
    make_ca(folder, "intruder")
    return folder


@pytest.fixture(scope="module")
def tls_cluster(certs):
    """A TLS LocalCluster of two worker processes: its scheduler's address."""
    c = {k: str(certs / f"cluster{k}.pem") for k in ("", "-key", "-ca")}
    security = distributed.Security(tls_ca_file=c["-ca"], tls_scheduler_cert=c[""], tls_scheduler_key=c["-key"],
                                    tls_worker_cert=c[""], tls_worker_key=c["-key"], tls_client_cert=c[""],
                                    tls_client_key=c["-key"], require_encryption=True)
    cluster = distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None,
                                       protocol="tls", security=security, host="127.0.0.1")
    with cluster:
        yield cluster.scheduler_address


@pytest.fixture(scope="module")
def local_rows(tmp_path_factory) -> bytes:
    out = tmp_path_factory.mktemp("local") / "rows.csv"
    sweep("paper-table-3-2", scale=GRID, workers=1, out=out)
    return out.read_bytes()


def tls_options(certs: Path, name: str = "cluster", ca: str = "cluster") -> list[str]:
    return ["--tls-ca-file", str(certs / f"{ca}-ca.pem"), "--tls-cert", str(certs / f"{name}.pem"),
            "--tls-key", str(certs / f"{name}-key.pem")]




def test_a_tls_cluster_runs_the_local_rows(tls_cluster, certs, local_rows, tmp_path, capsys):
    assert tls_cluster.startswith("tls://")
    out = tmp_path / "rows.csv"
    status, text, err = run(["sweep", *SCALE, "--scheduler", tls_cluster, *tls_options(certs), "--out", str(out)],
                            capsys)
    assert status == 0, err
    assert [line for line in err if not line.startswith("isolator sweep: ")] == []  # progress, should it be slow
    assert "designs: 6 (6 run now)" in text
    assert out.read_bytes() == local_rows
    # in Python: security= where the scheduler's address is taken
    security = tls_security(certs / "cluster-ca.pem", certs / "cluster.pem", certs / "cluster-key.pem")
    again = tmp_path / "again.csv"
    sweep("paper-table-3-2", scale=GRID, scheduler=tls_cluster, security=security, out=again)
    assert again.read_bytes() == local_rows


def test_dask_s_own_tls_configuration_keeps_working(tls_cluster, certs, local_rows, tmp_path, capsys):
    import dask

    files = {"distributed.comm.tls.ca-file": str(certs / "cluster-ca.pem"),
             "distributed.comm.tls.client.cert": str(certs / "cluster.pem"),
             "distributed.comm.tls.client.key": str(certs / "cluster-key.pem")}
    out = tmp_path / "rows.csv"
    with dask.config.set(files):
        status, _, err = run(["sweep", *SCALE, "--scheduler", tls_cluster, "--out", str(out)], capsys)
    assert status == 0, err
    assert out.read_bytes() == local_rows


BAD = {
    "tls:// without certificates": ([], "--tls-ca-file, --tls-cert, --tls-key: the scheduler tls://"),
    "a missing CA file": (["--tls-ca-file", "{certs}/nowhere.pem", "--tls-cert", "{certs}/cluster.pem",
                           "--tls-key", "{certs}/cluster-key.pem"], "--tls-ca-file: no such file"),
    "a folder for the certificate": (["--tls-ca-file", "{certs}/cluster-ca.pem", "--tls-cert", "{certs}",
                                      "--tls-key", "{certs}/cluster-key.pem"], "--tls-cert: '"),
    "a key that is no key": (["--tls-ca-file", "{certs}/cluster-ca.pem", "--tls-cert", "{certs}/cluster.pem",
                              "--tls-key", "{certs}/cluster.pem"], "--tls-key: '"),
    "another certificate's key": (["--tls-ca-file", "{certs}/cluster-ca.pem", "--tls-cert", "{certs}/cluster.pem",
                                   "--tls-key", "{certs}/intruder-key.pem"], "--tls-key: the certificate"),
    "two of the three": (["--tls-ca-file", "{certs}/cluster-ca.pem", "--tls-cert", "{certs}/cluster.pem"],
                         "--tls-key: TLS needs all three"),
    "a certificate the scheduler rejects": ("intruder", "--tls-cert: the scheduler tls://"),  # alert, or EOF
    "a CA that did not sign the scheduler": ("intruder-ca", "--tls-ca-file: the certificate of the scheduler"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_a_bad_certificate_is_one_line_naming_the_option(case, tls_cluster, certs, tmp_path, capsys):
    options, named = BAD[case]
    if options == "intruder":
        options = tls_options(certs, "intruder", ca="cluster")
    elif options == "intruder-ca":
        options = tls_options(certs, "cluster", ca="intruder")
    out = tmp_path / "rows.csv"
    argv = ["sweep", *SCALE, "--scheduler", tls_cluster, *[o.format(certs=certs) for o in options],
            "--out", str(out)]
    status, _, err = run(argv, capsys)
    assert status == 2
    assert len(err) == 1, err
    assert err[0].startswith(f"isolator: error: {named}"), err
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_an_unreadable_certificate_is_named(certs, tmp_path, capsys, monkeypatch):
    locked = tmp_path / "locked.pem"
    shutil.copy(certs / "cluster.pem", locked)
    locked.chmod(0)
    if os.geteuid() == 0:  # root reads any file: refused as a file system would refuse another user
        read_text = Path.read_text

        def refused(self: Path, *args: object, **kwargs: object) -> str:
            if self == locked:
                raise PermissionError(13, "Permission denied", str(self))
            return read_text(self, *args, **kwargs)  # type: ignore[arg-type]

        monkeypatch.setattr(Path, "read_text", refused)
    status, _, err = run(["sweep", *SCALE, "--scheduler", "tls://127.0.0.1:9", "--tls-ca-file",
                          str(certs / "cluster-ca.pem"), "--tls-cert", str(locked), "--tls-key",
                          str(certs / "cluster-key.pem"), "--out", str(tmp_path / "rows.csv")], capsys)
    assert status == 2
    assert err == [f"isolator: error: --tls-cert: cannot read '{locked}' (Permission denied)"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["locked.pem"]


def test_certificates_need_a_tls_scheduler(certs, tmp_path, capsys):
    out = tmp_path / "rows.csv"
    status, _, err = run(["sweep", *SCALE, *tls_options(certs), "--workers", "1", "--out", str(out)], capsys)
    assert (status, err) == (2, ["isolator: error: --tls-ca-file: only with --scheduler tls://HOST:PORT"])
    status, _, err = run(["sweep", *SCALE, "--scheduler", "tcp://127.0.0.1:9", *tls_options(certs), "--out",
                          str(out)], capsys)
    assert status == 2
    assert len(err) == 1
    assert "certificates given for the plain tcp:// scheduler" in err[0]
    assert not out.exists()


def test_python_names_its_arguments(tls_cluster, certs, tmp_path):
    with pytest.raises(ParameterError, match=r"^security: the scheduler tls://"):
        sweep("paper-table-3-2", scale=GRID, scheduler=tls_cluster)
    with pytest.raises(ParameterError, match=r"^security \(tls_ca_file\): no such file"):
        tls_security(certs / "nowhere.pem", certs / "cluster.pem", certs / "cluster-key.pem")
    with pytest.raises(ParameterError, match=r"^security: must be a distributed.Security"):
        sweep("paper-table-3-2", scale=GRID, scheduler=tls_cluster, security="certs.pem")
    from isolator import load_scenario
    from studies.robustness import run_robustness_study

    with pytest.raises(ParameterError, match=r"^security: the scheduler tls://"):
        run_robustness_study(tmp_path / "study", load_scenario("paper-table-3-2"), samples=2, scheduler=tls_cluster)
    assert not (tmp_path / "study").exists()


def test_the_robustness_study_takes_the_same_options(certs, tmp_path, capsys):
    out = tmp_path / "study"
    status, _, err = run(["study", "robustness", "--quick", "--samples", "2", "--scheduler", "tls://127.0.0.1:9",
                          "--out", str(out)], capsys)
    assert status == 2
    assert err[0].startswith("isolator: error: --tls-ca-file, --tls-cert, --tls-key: the scheduler tls://"), err
    assert not out.exists()
    status, _, err = run(["study", "robustness", "--quick", "--scheduler", "tls://127.0.0.1:9", "--tls-ca-file",
                          str(certs / "none.pem"), "--tls-cert", str(certs / "cluster.pem"), "--tls-key",
                          str(certs / "cluster-key.pem"), "--out", str(out)], capsys)
    assert (status, len(err)) == (2, 1)
    assert err[0].startswith("isolator: error: --tls-ca-file: no such file")
    assert not out.exists()


def _outward_address() -> str | None:
    """This machine's address on its network (None: it has only loopback)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.connect(("192.0.2.1", 9))  # no packet is sent: the route picks the address
        except OSError:
            return None
        address = str(s.getsockname()[0])
    return None if is_loopback(address) else address


def test_a_plain_scheduler_beyond_loopback_runs_with_one_warning(local_rows, tmp_path, capsys):
    host = _outward_address()
    if host is None:
        pytest.skip("this machine has no address but loopback")
    assert is_loopback("127.0.0.1")
    assert is_loopback("localhost")
    assert not is_loopback(host)
    out = tmp_path / "rows.csv"
    cluster = distributed.LocalCluster(n_workers=1, processes=False, threads_per_worker=2, dashboard_address=None,
                                       host=host, protocol="tcp")
    with cluster:
        status, _, err = run(["sweep", *SCALE, "--scheduler", cluster.scheduler_address, "--out", str(out)],
                             capsys)
    assert status == 0
    err = [line for line in err if not line.startswith("isolator sweep: ")]  # progress, should it be slow
    assert len(err) == 1, err
    assert err[0].startswith(f"isolator: warning: --scheduler {cluster.scheduler_address}: the connection is "
                             "unencrypted and unauthenticated")
    assert "--tls-ca-file" in err[0]
    assert out.read_bytes() == local_rows


def test_the_robustness_study_runs_on_the_tls_cluster(tls_cluster, certs, tmp_path, capsys):
    study = ["study", "robustness", "paper-table-3-2", "--quick", "--samples", "4", "--tolerance",
             "isolators[*].stiffness=+-10%"]
    assert main([*study, "--workers", "1", "--out", str(tmp_path / "local")]) == 0
    status, _, err = run([*study, "--scheduler", tls_cluster, *tls_options(certs), "--out", str(tmp_path / "tls")],
                         capsys)
    assert status == 0, err
    assert (tmp_path / "tls" / "samples.csv").read_bytes() == (tmp_path / "local" / "samples.csv").read_bytes()
