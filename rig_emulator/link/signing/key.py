"""The MAVLink 2 signing key of ``rig-emulator serve --signing-key`` / ``--signing-key-file``.

A signing key is 32 bytes. The ground stations derive it from a passphrase: MAVProxy's
``signing setup PASSPHRASE`` / ``signing key PASSPHRASE`` and QGroundControl both use the
SHA-256 digest of the passphrase, so the rig does the same:

* ``PASSPHRASE`` - any other text: the key is SHA-256 of its UTF-8 bytes (for ASCII
  passphrases, which is all MAVProxy accepts, exactly MAVProxy's key);
* ``hex:<64 hex digits>`` - the 32 key bytes themselves.

A key file holds one of these two forms on its first line (trailing newline and spaces
ignored); a group- or world-readable key file gets a warning. Nothing here ever puts the
key or the passphrase into an error message.
"""

from __future__ import annotations

import hashlib
import os
import stat
from pathlib import Path

from rig_emulator.config.loader import ConfigError

KEY_BYTES = 32
HEX_PREFIX = "hex:"


class SigningKeyError(ConfigError):
    """A signing key that cannot be used (the message never contains the key)."""


def key_from_passphrase(passphrase: str) -> bytes:
    """SHA-256 of the passphrase's UTF-8 bytes (MAVProxy's and QGroundControl's derivation)."""
    return hashlib.sha256(passphrase.encode("utf-8")).digest()


def parse_signing_key(text: str, source: str = "--signing-key") -> bytes:
    """The 32-byte key of ``hex:<64 hex digits>`` or of a passphrase."""
    if text.lower().startswith(HEX_PREFIX):
        digits = text[len(HEX_PREFIX):]
        if len(digits) != 2 * KEY_BYTES:
            raise SigningKeyError(f"{source}: hex: needs exactly {2 * KEY_BYTES} hex digits, got {len(digits)}")
        try:
            return bytes.fromhex(digits)
        except ValueError:
            raise SigningKeyError(f"{source}: hex: key has a character that is not a hex digit") from None
    if not text:
        raise SigningKeyError(f"{source}: empty passphrase")
    if text != text.strip():
        raise SigningKeyError(f"{source}: the passphrase starts or ends with white space "
                              "(ground stations would hash a different text)")
    return key_from_passphrase(text)


def read_key_file(path) -> tuple[bytes, str | None]:
    """(key, warning or None) from a key file's first line."""
    path = Path(path)
    try:
        data = path.read_bytes()
        mode = path.stat().st_mode
    except OSError as exc:
        raise SigningKeyError(f"--signing-key-file {path}: cannot read: {exc.strerror}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise SigningKeyError(f"--signing-key-file {path}: not UTF-8 text") from None
    lines = text.splitlines()
    first = lines[0].rstrip() if lines else ""
    key = parse_signing_key(first, f"--signing-key-file {path}")
    warning = None
    if os.name == "posix" and mode & (stat.S_IRWXG | stat.S_IRWXO):
        warning = f"signing key file {path} is readable by other users (chmod 600 it)"
    return key, warning
