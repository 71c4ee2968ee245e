"""BuildCache: built once per key, copies handed out, least recently used dropped, None not kept."""

import pytest

from rig_emulator.build_cache import BuildCache


def test_builds_once_per_key_and_hands_out_copies():
    cache, calls = BuildCache(2), []

    def build(v):
        def f():
            calls.append(v)
            return {"v": [v]}
        return f

    a = cache.get_or_build("a", build(1))
    a["v"].append(99)  # the caller's changes stay with the caller
    assert cache.get_or_build("a", build(2)) == {"v": [1]} and calls == [1]
    cache.get_or_build("b", build(3))
    cache.get_or_build("a", build(4))  # "a" is now the most recently used
    cache.get_or_build("c", build(5))  # drops "b"
    assert len(cache) == 2 and calls == [1, 3, 5]
    cache.get_or_build("b", build(6))
    assert calls == [1, 3, 5, 6]
    assert cache.get_or_build(None, build(7)) == {"v": [7]} and len(cache) == 2


def test_a_failed_build_keeps_nothing():
    cache = BuildCache(4)

    def bad():
        raise ValueError("no")

    with pytest.raises(ValueError):
        cache.get_or_build("k", bad)
    assert len(cache) == 0
    cache.clear()
