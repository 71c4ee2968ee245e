"""The compiled-code cache key covers every module that defines compiled code."""

from pathlib import Path

from rig_emulator import _jit


def test_every_jit_user_is_under_a_hashed_root():
    repo = Path(_jit.__file__).resolve().parent.parent
    hashed = {p.resolve() for p in _jit.compiled_source_files()}
    users = [
        p for pkg in ("rig_emulator", "protocol") for p in (repo / pkg).rglob("*.py")
        if "from rig_emulator._jit import jit" in p.read_text(encoding="utf-8")
    ]
    assert users, "no compiled modules found"
    outside = [str(p.relative_to(repo)) for p in users if p.resolve() not in hashed]
    assert not outside, f"compiled code outside COMPILED_ROOTS (its edits would not refresh the cache): {outside}"


def test_cache_dir_is_keyed_on_the_sources():
    assert Path(_jit.CACHE_DIR).name == "numba-" + _jit._source_digest()


def test_shared_logic_compiled_by_the_rig_is_hashed():
    # protocol/ holds the waypoint logic as plain Python; the rig compiles it, so its source
    # must key the cache like any compiled module's.
    from rig_emulator.guidance import waypoint_switching as compiled

    hashed = {p.resolve() for p in _jit.compiled_source_files()}
    for dispatcher in (compiled.leg_duration, compiled.line_setpoint, compiled.waypoint_reached):
        assert Path(dispatcher.py_func.__code__.co_filename).resolve() in hashed
