"""The optional parts of ``rig-emulator serve`` built from its options: MAVLink signing
(``--signing-key`` / ``--signing-key-file``) and the state directory (``--state-dir``,
``--no-persist``, ``--wipe``). Every problem is a ConfigError (exit code 2) raised before
the rig starts; nothing here prints the key.
"""

from __future__ import annotations

from rig_emulator.link.state.rig_state import RigState
from rig_emulator.link.signing.policy import UNSIGNED_ALLOWED, LinkSigning, message_name
from rig_emulator.link.signing.key import SigningKeyError, parse_signing_key, read_key_file
from rig_emulator.link.state.directory import DEFAULT_STATE_DIR, StateError


def signing_key_from_args(args, log) -> tuple[bytes | None, str]:
    """(key or None, where it came from) from ``--signing-key`` / ``--signing-key-file``."""
    if args.signing_key is not None and args.signing_key_file is not None:
        raise SigningKeyError("--signing-key and --signing-key-file: give one of them")
    if args.signing_key is not None:
        kind = "hex key" if args.signing_key.lower().startswith("hex:") else "passphrase"
        return parse_signing_key(args.signing_key), f"{kind} from --signing-key"
    if args.signing_key_file is not None:
        key, warning = read_key_file(args.signing_key_file)
        if warning:
            log(f"warning: {warning}")
        return key, f"key file {args.signing_key_file}"
    return None, ""


def open_state(args, home) -> RigState | None:
    """The locked state directory with its documents read (None with --no-persist)."""
    if args.no_persist:
        if args.wipe or args.state_dir is not None:
            raise StateError("--no-persist: not with --wipe or --state-dir")
        return None
    return RigState(args.state_dir or DEFAULT_STATE_DIR, home, wipe=args.wipe)


def make_signing(key: bytes | None, source: str, state: RigState | None, log) -> LinkSigning | None:
    if key is None:
        return None
    signing = LinkSigning(key, stored=state.signing_stored if state is not None else None,
                          save=state.save_signing if state is not None else None, log=log)
    allowed = ", ".join(sorted(message_name(i) for i in UNSIGNED_ALLOWED))
    log(f"MAVLink 2 signing on ({source}): every message sent is signed; messages received must be "
        f"signed with the key (unsigned accepted: {allowed})")
    return signing
