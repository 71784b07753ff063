"""HTTPS: with `[server] tls_certfile` and `tls_keyfile`, `proxima serve` answers only
over TLS (a certificate for 127.0.0.1 made here with `cryptography`), and the 3D view's
cookie is Secure; a half or missing pair is refused with the field named."""

from __future__ import annotations

import datetime
import ipaddress
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest
from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import NameOID

from proxima.settings import Settings, SettingsError


def make_certificate(folder: Path) -> tuple[Path, Path]:
    """A self-signed certificate for 127.0.0.1 and its key, as PEM files."""
    key = ec.generate_private_key(ec.SECP256R1())
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "proxima test")])
    now = datetime.datetime.now(datetime.UTC)
    cert = (
        x509.CertificateBuilder()
        .subject_name(name)
        .issuer_name(name)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - datetime.timedelta(minutes=1))
        .not_valid_after(now + datetime.timedelta(days=1))
        .add_extension(
            x509.SubjectAlternativeName([x509.IPAddress(ipaddress.ip_address("127.0.0.1"))]),
            critical=False,
        )
        .add_extension(x509.BasicConstraints(ca=True, path_length=None), critical=True)
        .sign(key, hashes.SHA256())
    )
    cert_file, key_file = folder / "console.crt", folder / "console.key"
    cert_file.write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    key_file.write_bytes(
        key.private_bytes(
            serialization.Encoding.PEM,
            serialization.PrivateFormat.PKCS8,
            serialization.NoEncryption(),
        )
    )
    key_file.chmod(0o600)
    return cert_file, key_file


def test_a_half_or_missing_pair_is_refused(tmp_path: Path) -> None:
    cert, key = make_certificate(tmp_path)
    with pytest.raises(SettingsError, match="both tls_certfile and tls_keyfile"):
        Settings.load(config=None, server={"tls_certfile": str(cert)})
    with pytest.raises(SettingsError, match="tls_keyfile: no such file"):
        Settings.load(config=None, server={"tls_certfile": str(cert), "tls_keyfile": "nope.key"})
    ok = Settings.load(config=None, server={"tls_certfile": str(cert), "tls_keyfile": str(key)})
    assert ok.server.tls


@pytest.mark.slow
@pytest.mark.timeout(120)
def test_serve_over_https(tmp_path: Path) -> None:
    cert, key = make_certificate(tmp_path)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = {
        **os.environ,
        "PROXIMA_ADMIN_USER": "chief",
        "PROXIMA_ADMIN_PASSWORD": "correct-horse-battery",
        "PROXIMA_SERVER__DB_PATH": str(tmp_path / "serve.db"),
        "PROXIMA_SERVER__VISER_ENABLED": "false",
        "PROXIMA_SERVER__TLS_CERTFILE": str(cert),
        "PROXIMA_SERVER__TLS_KEYFILE": str(key),
        "PROXIMA_TRAINING__ENABLED": "false",
    }
    env.pop("PROXIMA_CONFIG", None)
    proc = subprocess.Popen(
        [sys.executable, "-m", "proxima.cli", "serve", "--port", str(port)],
        cwd=tmp_path,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        url = f"https://127.0.0.1:{port}"
        deadline = time.monotonic() + 60
        while True:
            try:
                if httpx.get(f"{url}/api/health", verify=str(cert), timeout=2).is_success:
                    break
            except httpx.HTTPError:
                pass
            assert proc.poll() is None, proc.stdout.read() if proc.stdout else ""
            assert time.monotonic() < deadline, "serve did not come up over HTTPS"
            time.sleep(0.3)
        r = httpx.post(
            f"{url}/api/auth/login",
            json={"username": "chief", "password": "correct-horse-battery"},
            verify=str(cert),
        )
        assert r.status_code == 200
        assert "secure" in r.headers["set-cookie"].lower()
        # Plain HTTP on the same port gets no answer from the console.
        with pytest.raises(httpx.HTTPError):
            httpx.get(f"http://127.0.0.1:{port}/api/health", timeout=3)
        # A client that does not trust the certificate refuses it.
        with pytest.raises(httpx.ConnectError):
            httpx.get(f"{url}/api/health", timeout=3)
    finally:
        proc.send_signal(signal.SIGTERM)
        try:
            out, _ = proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            out, _ = proc.communicate()
    assert proc.returncode == 0, out
    assert f"Proxima console: https://127.0.0.1:{port}/" in out
