"""The beam kernels' named data: packed into two arrays and read back by the annotations of
the NamedTuple, the same in compiled code and in Python."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pytest
from numba import njit

from liegroup_int.problems.beam.kernels.adapters import F1, F2, F3, F4, I1, I2, field_readers, pack, unpack_as


class Sample(NamedTuple):
    a: F1
    b: F2
    c: F3
    d: F4
    j: I1
    k: I2
    x: float
    n: int
    flag: bool
    empty: F2


def _sample() -> Sample:
    rng = np.random.default_rng(3)
    return Sample(rng.normal(size=4), rng.normal(size=(2, 3)), rng.normal(size=(2, 1, 3)),
                  rng.normal(size=(1, 2, 2, 2)), np.array([5, -1, 7]), np.arange(6).reshape(3, 2), 2.5, -4, True,
                  np.zeros((0, 3)))


@njit(cache=True)
def _compiled(flat, head):
    return unpack_as(Sample, flat, head)


@pytest.mark.parametrize("read", [unpack_as, lambda cls, flat, head: _compiled(flat, head)], ids=["python", "numba"])
def test_packed_data_read_back_by_annotation(read):
    data = _sample()
    flat, head = pack(data)
    back = read(Sample, flat, head)
    for name, want, got in zip(Sample._fields, data, back):
        assert np.asarray(got).shape == np.asarray(want).shape, name
        assert np.array_equal(got, want), name
        assert type(got) is type(want) or isinstance(got, np.ndarray), name


def test_python_views_share_the_packed_arrays():
    flat, head = pack(_sample())
    back = unpack_as(Sample, flat, head)
    back.b[1, 2] = 99.0
    assert 99.0 in flat


def test_readers_follow_annotations_and_a_mismatch_is_refused():
    assert field_readers(Sample) == ("f1", "f2", "f3", "f4", "i1", "i2", "fs", "is_", "bs", "f2")
    with pytest.raises(ValueError, match=r"Sample\.b: a float64 array of 1 dimensions, annotated f2"):
        pack(_sample()._replace(b=np.ones(3)))
    with pytest.raises(ValueError, match=r"Sample\.j: a float64 array"):
        pack(_sample()._replace(j=np.ones(3)))

    class Bad(NamedTuple):
        a: np.ndarray

    with pytest.raises(TypeError, match=r"Bad\.a: annotate with"):
        field_readers(Bad)
