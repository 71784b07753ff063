"""Certificates and keys for a secured federation: a CA, the SuperLink's TLS certificate
signed by it, and one EC key pair per drone for Flower's SuperNode authentication.

Flower (1.41, 1.42) wants: on the SuperLink a PEM CA certificate, server certificate and key
(`--ssl-ca-certfile/--ssl-certfile/--ssl-keyfile`); on each SuperNode the CA certificate
(`--root-certificates`) and an OpenSSH EC private key on a NIST curve
(`--auth-supernode-private-key`); its OpenSSH public key is registered on the SuperLink
(`flwr supernode register`). The server certificate must name, as subject alternative
names, every address a client dials: the drones' (the ground station's IP or host name)
and 127.0.0.1, which the SuperLink's own SuperExec and the `flwr` CLI use.

`proxima fl pki` writes a fleet's set; the local deployment makes a throwaway one in its
working folder. Private keys are written with mode 0600.
"""

from __future__ import annotations

import datetime as dt
import ipaddress
import os
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from cryptography import x509
from cryptography.exceptions import UnsupportedAlgorithm
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

CURVE = ec.SECP384R1  # P-384: what Flower's docs use for SuperNode keys
LOOPBACK_NAMES = ("127.0.0.1", "localhost")
_NAME = re.compile(r"^[A-Za-z0-9_.-]+$")


class PKIError(ValueError):
    """A certificate or key file that cannot be used; the message names the file."""


@dataclass(frozen=True)
class ServerCredentials:
    """What the SuperLink needs for TLS (PEM files)."""

    ca_cert: Path
    cert: Path
    key: Path


@dataclass(frozen=True)
class DroneKey:
    """A drone's SuperNode key pair (OpenSSH format): the private key stays on the drone,
    the public key is registered on the SuperLink."""

    name: str
    private_key: Path
    public_key: Path


def _write(path: Path, data: bytes, private: bool = False) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    if private:  # never readable by others, not even for a moment
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.chmod(path, 0o600)
    else:
        path.write_bytes(data)
    return path


def _pem_key(key: ec.EllipticCurvePrivateKey) -> bytes:
    return key.private_bytes(
        serialization.Encoding.PEM,
        serialization.PrivateFormat.PKCS8,
        serialization.NoEncryption(),
    )


def _san(names: Iterable[str]) -> list[x509.GeneralName]:
    out: list[x509.GeneralName] = []
    for name in dict.fromkeys(n.strip() for n in names if n.strip()):
        try:
            out.append(x509.IPAddress(ipaddress.ip_address(name)))
        except ValueError:
            out.append(x509.DNSName(name))
    return out


def make_ca(folder: Path, name: str = "Proxima fleet CA", days: int = 3650) -> tuple[Path, Path]:
    """A self-signed CA certificate and key: `ca.crt`, `ca.key` in `folder`. The CA key
    signs the SuperLink's certificate; keep it off the drones (and offline for a fleet)."""
    key = ec.generate_private_key(CURVE())
    subject = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, name)])
    now = dt.datetime.now(dt.UTC)
    cert = (
        x509.CertificateBuilder()
        .subject_name(subject)
        .issuer_name(subject)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - dt.timedelta(minutes=5))
        .not_valid_after(now + dt.timedelta(days=days))
        .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
        .add_extension(
            x509.KeyUsage(
                digital_signature=True,
                key_cert_sign=True,
                crl_sign=True,
                content_commitment=False,
                key_encipherment=False,
                data_encipherment=False,
                key_agreement=False,
                encipher_only=False,
                decipher_only=False,
            ),
            critical=True,
        )
        .add_extension(x509.SubjectKeyIdentifier.from_public_key(key.public_key()), False)
        .sign(key, hashes.SHA384())
    )
    ca_cert = _write(folder / "ca.crt", cert.public_bytes(serialization.Encoding.PEM))
    ca_key = _write(folder / "ca.key", _pem_key(key), private=True)
    return ca_cert, ca_key


def _load_ca(ca_cert: Path, ca_key: Path) -> tuple[x509.Certificate, ec.EllipticCurvePrivateKey]:
    try:
        cert = x509.load_pem_x509_certificate(Path(ca_cert).read_bytes())
    except (OSError, ValueError) as exc:
        raise PKIError(f"{ca_cert}: not a readable PEM certificate ({exc})") from None
    try:
        key = serialization.load_pem_private_key(Path(ca_key).read_bytes(), password=None)
    except (OSError, ValueError, TypeError) as exc:
        raise PKIError(f"{ca_key}: not a readable, unencrypted PEM key ({exc})") from None
    if not isinstance(key, ec.EllipticCurvePrivateKey):
        raise PKIError(f"{ca_key}: expected an EC private key")
    return cert, key


def make_server_cert(
    folder: Path, ca_cert: Path, ca_key: Path, names: Iterable[str], days: int = 825
) -> ServerCredentials:
    """The SuperLink's certificate (`server.pem`) and key (`server.key`), signed by the
    CA, valid for `names` (IP addresses or host names) plus 127.0.0.1 and localhost.

    Raises:
        PKIError: the CA files cannot be read.
    """
    ca, signer = _load_ca(ca_cert, ca_key)
    key = ec.generate_private_key(CURVE())
    all_names = [*names, *LOOPBACK_NAMES]
    first = next(iter(n for n in all_names if n.strip()))
    now = dt.datetime.now(dt.UTC)
    cert = (
        x509.CertificateBuilder()
        .subject_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, first)]))
        .issuer_name(ca.subject)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - dt.timedelta(minutes=5))
        .not_valid_after(now + dt.timedelta(days=days))
        .add_extension(x509.SubjectAlternativeName(_san(all_names)), critical=False)
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .add_extension(x509.ExtendedKeyUsage([ExtendedKeyUsageOID.SERVER_AUTH]), False)
        .sign(signer, hashes.SHA384())
    )
    cert_path = _write(folder / "server.pem", cert.public_bytes(serialization.Encoding.PEM))
    key_path = _write(folder / "server.key", _pem_key(key), private=True)
    ca_copy = folder / "ca.crt"
    if ca_copy.resolve() != Path(ca_cert).resolve():
        _write(ca_copy, Path(ca_cert).read_bytes())
    return ServerCredentials(ca_copy, cert_path, key_path)


def make_drone_key(folder: Path, name: str) -> DroneKey:
    """A drone's SuperNode key pair: `<name>.key` (OpenSSH private key, mode 0600) and
    `<name>.pub` (OpenSSH public key, e.g. `ecdsa-sha2-nistp384 AAAA... name`).

    Raises:
        PKIError: a name that is not a plain file name.
    """
    if not _NAME.match(name):
        raise PKIError(f"drone name {name!r}: letters, digits, '.', '_' and '-' only")
    key = ec.generate_private_key(CURVE())
    private = key.private_bytes(
        serialization.Encoding.PEM,
        serialization.PrivateFormat.OpenSSH,
        serialization.NoEncryption(),
    )
    public = key.public_key().public_bytes(
        serialization.Encoding.OpenSSH, serialization.PublicFormat.OpenSSH
    )
    priv_path = _write(folder / f"{name}.key", private, private=True)
    pub_path = _write(folder / f"{name}.pub", public + f" {name}\n".encode())
    return DroneKey(name, priv_path, pub_path)


def check_public_key(path: Path) -> None:
    """Refuse a file that is not an OpenSSH EC public key on a NIST curve (what Flower
    registers), before any process starts.

    Raises:
        PKIError: missing, unreadable, or another key type (the file named).
    """
    try:
        key = serialization.load_ssh_public_key(Path(path).read_bytes())
    except OSError as exc:
        raise PKIError(f"{path}: cannot read the public key ({exc.strerror})") from None
    except (ValueError, UnsupportedAlgorithm) as exc:
        raise PKIError(f"{path}: not an OpenSSH public key ({exc})") from None
    if not isinstance(key, ec.EllipticCurvePublicKey):
        kind = type(key).__name__
        raise PKIError(f"{path}: expected an EC key (ecdsa-sha2-nistp384), got {kind}")


def check_server_files(creds: ServerCredentials) -> None:
    """Refuse missing or malformed SuperLink TLS files before the SuperLink starts.

    Raises:
        PKIError: the file that cannot be used, named.
    """
    for path in (creds.ca_cert, creds.cert):
        try:
            x509.load_pem_x509_certificate(Path(path).read_bytes())
        except (OSError, ValueError) as exc:
            raise PKIError(f"{path}: not a readable PEM certificate ({exc})") from None
    try:
        serialization.load_pem_private_key(Path(creds.key).read_bytes(), password=None)
    except (OSError, ValueError, TypeError) as exc:
        raise PKIError(f"{creds.key}: not a readable, unencrypted PEM key ({exc})") from None


def throwaway_pki(
    folder: Path, drones: Iterable[str], server: bool = True
) -> tuple[ServerCredentials | None, list[DroneKey]]:
    """A fresh CA with a loopback server certificate (unless `server` is false) and one
    key pair per drone in `folder`: the local deployment's, remade at every start;
    nothing outside trusts this CA."""
    creds = None
    if server:
        ca_cert, ca_key = make_ca(folder / "ca", name="Proxima local CA (throwaway)", days=30)
        creds = make_server_cert(folder / "superlink", ca_cert, ca_key, LOOPBACK_NAMES, days=30)
    keys = [make_drone_key(folder / "drones", name) for name in drones]
    return creds, keys
