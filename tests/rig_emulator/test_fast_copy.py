"""fast_deepcopy gives what copy.deepcopy gives on plain data: equal values, nothing shared
with the original, sharing inside kept, array layout, dtype and writeability kept."""

import copy
from collections import namedtuple

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rig_emulator.fast_copy import fast_deepcopy

P = namedtuple("P", "a b")

scalars = st.one_of(st.none(), st.booleans(), st.integers(), st.floats(allow_nan=False), st.text(max_size=5))
arrays = st.builds(lambda shape, f: np.full(shape, f), st.lists(st.integers(0, 3), max_size=3).map(tuple),
                   st.floats(allow_nan=False, width=64))
leaves = st.one_of(scalars, arrays)
trees = st.recursive(leaves, lambda kids: st.one_of(
    st.lists(kids, max_size=4),
    st.dictionaries(st.text(max_size=4), kids, max_size=4),
    st.tuples(kids, kids),
    st.builds(P, kids, kids),
), max_leaves=20)


def _same(a, b):
    assert type(a) is type(b)
    if isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape and a.strides == b.strides and np.array_equal(a, b)
        assert a.size == 0 or not np.shares_memory(a, b)
    elif isinstance(a, dict):
        assert a.keys() == b.keys()
        for k in a:
            _same(a[k], b[k])
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b)
        for x, y in zip(a, b):
            _same(x, y)
        if isinstance(a, list):
            assert a is not b
    else:
        assert a == b


@settings(max_examples=200, deadline=None)
@given(trees)
def test_equal_to_the_original_and_independent_of_it(tree):
    _same(tree, fast_deepcopy(tree))
    _same(copy.deepcopy(tree), fast_deepcopy(tree))


def test_sharing_layout_and_writeability_are_kept():
    shared = np.arange(6.0).reshape(2, 3)
    fortran = np.asfortranarray(np.ones((3, 2)))
    ro = np.zeros(3)
    ro.flags.writeable = False
    lst = [1, 2]
    tree = {"p": P(shared, fortran), "q": P(shared, ro), "l": lst, "again": lst}
    out = fast_deepcopy(tree)
    assert out["p"].a is out["q"].a and out["p"].a is not shared
    out["p"].a[0, 0] = 99.0
    assert out["q"].a[0, 0] == 99.0 and shared[0, 0] == 0.0
    assert out["p"].b.flags.f_contiguous and not out["p"].b.flags.c_contiguous
    assert not out["q"].b.flags.writeable
    assert out["l"] is out["again"] and out["l"] is not lst


def test_other_objects_go_to_deepcopy_with_the_same_memo():
    rng = np.random.default_rng(3)
    arr = np.ones(2)

    class Box:
        def __init__(self):
            self.arr = arr

    out = fast_deepcopy({"rng": rng, "box": Box(), "arr": arr})
    assert out["rng"] is not rng and out["rng"].random() == np.random.default_rng(3).random()
    assert out["box"].arr is out["arr"]  # one copy of the array, reached from both
