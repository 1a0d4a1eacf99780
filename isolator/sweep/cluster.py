"""A Dask scheduler's address to a client, checked before any work: TLS certificates (the options Dask's own
command line names ``--tls-ca-file``, ``--tls-cert``, ``--tls-key``; or Dask's configuration), a plain
``tcp://`` scheduler beyond this machine warned about, every failure one :class:`ParameterError` naming the
option to fix.

A ``tls://`` scheduler needs a CA certificate (which scheduler to trust) and this client's certificate and
key, signed by a CA the scheduler trusts (Dask's TLS is mutual: the scheduler lets in only holders of such a
certificate). Dask's configuration (``distributed.comm.tls.ca-file``, ``.client.cert``, ``.client.key``, also
as ``DASK_DISTRIBUTED__COMM__TLS__...`` environment variables) keeps working when no certificate is given.
"""

from __future__ import annotations

import asyncio
import ipaddress
import os
import socket
import ssl
import threading
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from isolator.errors import ParameterError

__all__ = ["PYTHON_NAMES", "SCHEDULER_TIMEOUT", "UNENCRYPTED_WARNING", "connect", "import_distributed", "is_loopback",
           "tls_security"]

#: how long [s] to try reaching a Dask scheduler
SCHEDULER_TIMEOUT = 5.0
#: how :func:`connect` names the inputs in its messages: the keyword arguments of the Python functions
PYTHON_NAMES: Mapping[str, str] = {"scheduler": "scheduler", "ca": "security (tls_ca_file)",
                                   "cert": "security (tls_client_cert)", "key": "security (tls_client_key)",
                                   "tls": "security"}
#: the warning for a plain ``tcp://`` scheduler that is not on this machine ({address}, then how to use TLS)
UNENCRYPTED_WARNING = ("{option} {address}: the connection is unencrypted and unauthenticated: anyone who can "
                       "reach the scheduler runs code on its workers; on a shared network use a tls:// "
                       "scheduler ({tls})")


def import_distributed(option: str) -> Any:
    """Dask's ``distributed`` module; without it one line naming ``option`` and the extra to install."""
    try:
        import distributed
    except ImportError:
        raise ParameterError(f"{option}: needs Dask's distributed: pip install 'isolator[dask]'") from None
    return distributed


def is_loopback(host: str) -> bool:
    """Whether ``host`` (a name or an IP address) is this machine's loopback only (127.0.0.0/8, ::1)."""
    host = host.strip("[]")
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        pass
    try:
        found = socket.getaddrinfo(host, None)
    except (OSError, UnicodeError):
        return False
    return bool(found) and all(ipaddress.ip_address(str(a[4][0]).split("%")[0]).is_loopback for a in found)


def _split(address: str, option: str) -> tuple[str, str]:
    """The protocol (``tcp`` without one, as Dask takes it) and host of ``PROTOCOL://HOST:PORT``."""
    protocol, sep, rest = address.partition("://")
    if not sep:
        protocol, rest = "tcp", address
    host = rest.rsplit(":", 1)[0] if ":" in rest and not rest.endswith("]") else rest
    if not host:
        raise ParameterError(f"{option}: expected PROTOCOL://HOST:PORT (tls://scheduler:8786), got '{address}'")
    return protocol.lower(), host


def _readable(path: str | os.PathLike[str], option: str, marker: str, what: str) -> str:
    """A PEM file that exists and can be read, holding ``marker``; its path as str."""
    file = Path(path)
    if not file.exists():
        raise ParameterError(f"{option}: no such file '{file}'")
    if not file.is_file():
        raise ParameterError(f"{option}: '{file}' is not a file")
    try:
        text = file.read_text(encoding="ascii", errors="replace")
    except OSError as exc:
        raise ParameterError(f"{option}: cannot read '{file}' ({exc.strerror or exc})") from None
    if marker not in text:
        raise ParameterError(f"{option}: '{file}' holds no {what} (a PEM file with '-----BEGIN {marker}')")
    return str(file)


def tls_security(ca_file: str | os.PathLike[str], cert: str | os.PathLike[str], key: str | os.PathLike[str],
                 names: Mapping[str, str] = PYTHON_NAMES) -> Any:
    """A :class:`distributed.Security` for a client of a TLS scheduler, its files checked.

    Parameters
    ----------
    ca_file : path
        The CA certificate(s) the scheduler's certificate must be signed by (PEM).
    cert, key : path
        This client's certificate (signed by a CA the scheduler trusts) and its private key (PEM; the key
        unencrypted, as Dask reads it).
    names : mapping of str to str
        How messages name the three (keys ``ca``, ``cert``, ``key``).

    Raises
    ------
    ParameterError
        A file missing or unreadable, not PEM, or a key that is not the certificate's, named.
    """
    distributed = import_distributed(names["ca"])
    ca = _readable(ca_file, names["ca"], "CERTIFICATE", "certificate")
    mine = _readable(cert, names["cert"], "CERTIFICATE", "certificate")
    secret = _readable(key, names["key"], "PRIVATE KEY", "private key")
    if _encrypted(secret):
        raise ParameterError(f"{names['key']}: '{secret}' is encrypted: its passphrase would be asked for on the "
                             "terminal; give the key unencrypted (openssl pkey -in KEY.pem -out plain.pem), "
                             "readable by you only")
    try:
        ssl.create_default_context(cafile=ca)
    except ssl.SSLError as exc:
        raise ParameterError(f"{names['ca']}: '{ca}' is not a CA certificate OpenSSL reads ({exc.reason})") from None
    try:  # a password callback: OpenSSL never prompts on the terminal
        ssl.create_default_context().load_cert_chain(mine, secret, password=_no_passphrase)
    except ssl.SSLError as exc:
        which = names["key"] if "KEY" in str(exc.reason) else names["cert"]
        raise ParameterError(f"{which}: the certificate '{mine}' and key '{secret}' do not go together "
                             f"({exc.reason or exc})") from None
    return distributed.Security(tls_ca_file=ca, tls_client_cert=mine, tls_client_key=secret,
                                require_encryption=True)


def _encrypted(key: str) -> bool:
    """Whether a PEM private key is encrypted (PKCS#8 ``ENCRYPTED PRIVATE KEY`` or a legacy ``Proc-Type``)."""
    text = Path(key).read_text(encoding="ascii", errors="replace")
    return "ENCRYPTED PRIVATE KEY" in text or "Proc-Type: 4,ENCRYPTED" in text


def _no_passphrase() -> bytes:
    raise ssl.SSLError("KEY_ENCRYPTED: the key needs a passphrase")


def connect(address: str, security: Any = None, *, timeout: float | None = None,
            names: Mapping[str, str] = PYTHON_NAMES) -> Any:
    """A :class:`distributed.Client` of the scheduler at ``address``, every problem one clear line.

    Parameters
    ----------
    address : str
        ``tls://HOST:PORT`` (with ``security``, or Dask's TLS configuration) or ``tcp://HOST:PORT``: one
        warning when HOST is not this machine's loopback.
    security : distributed.Security, optional
        TLS certificates (:func:`tls_security` checks files first); for ``tls://`` only.
    timeout : float, optional
        How long to try reaching the scheduler [s] (default :data:`SCHEDULER_TIMEOUT`).
    names : mapping of str to str
        How messages name the inputs (keys ``scheduler``, ``tls`` for the certificates; ``ca``, ``cert``,
        ``key``): the Python arguments by default, the command's options from the command line.

    Raises
    ------
    ParameterError
        Naming the input: no Dask, a malformed address, ``tls://`` without certificates, certificates for a
        ``tcp://`` scheduler, a certificate the scheduler rejects (or a scheduler the CA does not sign), a
        scheduler not reached within ``timeout``.
    """
    option = names["scheduler"]
    timeout = SCHEDULER_TIMEOUT if timeout is None else timeout
    if not isinstance(address, str):
        raise ParameterError(f"{option}: must be an address 'tls://HOST:PORT', got {type(address).__name__}")
    distributed = import_distributed(option)
    protocol, host = _split(address, option)
    if security is not None and not isinstance(security, distributed.Security):
        raise ParameterError(f"{names['tls']}: must be a distributed.Security, got {type(security).__name__}")
    configured = security if security is not None else distributed.Security()
    has_tls = bool(configured.tls_ca_file and configured.tls_client_cert)
    if protocol == "tls" and not has_tls:
        raise ParameterError(f"{names['tls']}: the scheduler {address} speaks TLS: give its CA certificate and "
                             "this client's certificate and key (or set Dask's distributed.comm.tls "
                             "configuration)")
    if protocol == "tcp" and security is not None and has_tls:
        raise ParameterError(f"{names['tls']}: certificates given for the plain tcp:// scheduler {address}: "
                             "start the scheduler with --protocol tls and give its tls:// address")
    if protocol == "tcp" and not is_loopback(host):
        how = "--tls-ca-file, --tls-cert, --tls-key" if names["tls"].startswith("--") else "security="
        warnings.warn(UNENCRYPTED_WARNING.format(option=option, address=address, tls=f"{how}; see the recipe in "
                                                 "docs/guide/sweeps.md"), stacklevel=2)
    _probe(distributed, address, configured, timeout, names)
    try:  # after the probe: a scheduler that answers (a refused one never gets a Client to close at exit)
        return distributed.Client(address, timeout=timeout, security=security, set_as_default=False)
    except Exception as exc:  # Dask raises many kinds: each is one line naming what to fix
        raise ParameterError(_failure(address, exc, timeout, names)) from None


def _probe(distributed: Any, address: str, security: Any, timeout: float, names: Mapping[str, str]) -> None:
    """Connect to ``address`` and read the scheduler's handshake within ``timeout`` s (Dask's own connect
    waits for the handshake for ever: a peer that accepts and says nothing would hang the command); a
    failure is one :class:`ParameterError` naming the address."""
    async def handshake() -> None:
        comm = await distributed.comm.connect(address, timeout=timeout, **security.get_connection_args("client"))
        await comm.close()

    failure: list[BaseException] = []

    def run() -> None:  # its own event loop, in a thread: the caller may be running one (a notebook)
        try:
            asyncio.run(asyncio.wait_for(handshake(), timeout + 1.0))  # Dask's own connect error first
        except BaseException as exc:  # reported in the caller's thread
            failure.append(exc)

    thread = threading.Thread(target=run, name="isolator-scheduler-probe", daemon=True)
    thread.start()
    thread.join(timeout + 2.0)
    if thread.is_alive() or (failure and isinstance(failure[0], asyncio.TimeoutError | TimeoutError)):
        raise ParameterError(f"{names['scheduler']}: {address} accepted the connection but did not answer as a "
                             f"Dask scheduler within {timeout:g} s (another service on that port, or a scheduler "
                             "that hangs)")
    if failure:
        raise ParameterError(_failure(address, failure[0] if isinstance(failure[0], Exception) else
                                      RuntimeError(str(failure[0])), timeout, names)) from None


def _failure(address: str, exc: Exception, timeout: float, names: Mapping[str, str]) -> str:
    """What went wrong reaching the scheduler, naming the input to fix."""
    text = str(exc)
    if "UNKNOWN_CA" in text or "CERTIFICATE_REQUIRED" in text or "BAD_CERTIFICATE" in text \
            or "certificate unknown" in text.lower():
        return (f"{names['cert']}: the scheduler {address} rejected this certificate (not signed by a CA it "
                "trusts)")
    if "SSLEOFError" in text or "EOF occurred in violation of protocol" in text:  # the alert lost in the race
        return (f"{names['cert']}: the scheduler {address} ended the TLS handshake: it rejects this certificate "
                "(not signed by a CA it trusts), or does not speak TLS")
    if "certificate does not match" in text or "CERTIFICATE_VERIFY_FAILED" in text:
        return (f"{names['ca']}: the certificate of the scheduler {address} is not signed by this CA (or the "
                "scheduler is another one)")
    if "ssl_context" in text or "SSL" in text or "TLS" in text:
        return f"{names['tls']}: TLS with the scheduler {address} failed ({type(exc).__name__}: {text[:200]})"
    return (f"{names['scheduler']}: cannot reach a Dask scheduler at {address} within {timeout:g} s "
            f"({type(exc).__name__})")
