"""Signing keys: MAVProxy's passphrase derivation, hex keys, key files, errors that never show the key;
the signing clock."""

import hashlib
import os
import time

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rig_emulator.link.signing.clock import SigningClock, wall_timestamp
from rig_emulator.link.signing.key import SigningKeyError, parse_signing_key, read_key_file


def test_passphrase_gives_mavproxys_key():
    from MAVProxy.modules.mavproxy_signing import SigningModule

    mavproxy_key = SigningModule.passphrase_to_key(None, "hilms rig 42")  # the method uses nothing of self
    assert parse_signing_key("hilms rig 42") == mavproxy_key == hashlib.sha256(b"hilms rig 42").digest()


def test_hex_key():
    key = bytes(range(32))
    assert parse_signing_key("hex:" + key.hex()) == key
    assert parse_signing_key("HEX:" + key.hex().upper()) == key


@pytest.mark.parametrize("text, words", [
    ("hex:" + "ab" * 31, "64 hex digits, got 62"),
    ("hex:" + "zz" * 32, "not a hex digit"),
    ("", "empty passphrase"),
    (" secret", "white space"),
])
def test_bad_keys_are_refused_without_showing_them(text, words):
    with pytest.raises(SigningKeyError) as err:
        parse_signing_key(text)
    assert words in str(err.value)
    secret = text.partition(":")[2] if text.startswith("hex:") else text.strip()
    assert not secret or secret not in str(err.value)


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=80))
def test_any_text_is_a_key_or_a_clean_error(text):
    try:
        key = parse_signing_key(text)
    except SigningKeyError as exc:
        # the message never shows the key; a key of a few characters can match a few characters of the
        # message's own words (")" of "text)", once), so only keys of 8 or more characters are looked for
        secret = text[4:] if text.startswith("hex:") else text
        if len(secret.strip()) >= 8:
            assert secret not in str(exc) and secret.strip() not in str(exc)
    else:
        assert len(key) == 32


def test_key_file(tmp_path):
    path = tmp_path / "rig.key"
    path.write_text("hilms rig 42\n")
    os.chmod(path, 0o600)
    assert read_key_file(path) == (hashlib.sha256(b"hilms rig 42").digest(), None)
    os.chmod(path, 0o644)
    key, warning = read_key_file(path)
    assert key == hashlib.sha256(b"hilms rig 42").digest() and "readable by other users" in warning
    with pytest.raises(SigningKeyError, match="cannot read"):
        read_key_file(tmp_path / "missing.key")
    path.write_bytes(b"\xff\xfe")
    with pytest.raises(SigningKeyError, match="not UTF-8"):
        read_key_file(path)


def test_clock_follows_wall_time_never_goes_back_and_starts_after_the_stored_value():
    now = wall_timestamp()
    assert abs(now - (time.time() - 1420070400) * 1e5) < 1e5  # 10 us units since 2015-01-01
    clock = SigningClock()
    stamps = [clock.next() for _ in range(1000)]
    assert all(b > a for a, b in zip(stamps, stamps[1:])) and abs(stamps[0] - now) < 1e5
    ahead = now + 3600 * 100_000  # a stored timestamp an hour ahead of this host's clock
    clock = SigningClock(ahead)
    assert clock.next() == ahead + 1
    clock.observe(ahead + 500)
    assert clock.next() == ahead + 501
    with pytest.raises(ValueError):
        SigningClock(2**48)


def test_serve_refuses_bad_key_options_with_exit_code_2(tmp_path, capsys):
    from rig_emulator.cli import main

    secret = "hex:" + "5f" * 31 + "zz"
    for args, words in ((["--signing-key", secret], "not a hex digit"),
                        (["--signing-key", "a", "--signing-key-file", str(tmp_path / "k")], "give one of them"),
                        (["--signing-key-file", str(tmp_path / "missing.key")], "cannot read")):
        assert main(["serve", "--no-persist", "--duration", "0.1", *args]) == 2
        err = capsys.readouterr().err
        assert words in err and "5f5f" not in err, err
