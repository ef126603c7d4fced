"""What ties the beam kernels to their callers: named data in two flat arrays, and the
compiled engine's state and increment views (one factory, :func:`engine_kernels`).

Named data. Each formulation's kernels read a NamedTuple of arrays and scalars
(:class:`~.collocation.CollocationData`, :class:`~.galerkin.GalerkinData`). A numba call
unboxes a NamedTuple of 20 arrays in ~5 us (a plain array in ~0.1 us), more than a whole
stage rate at small ``n``, so the data cross into compiled code as two arrays: ``flat``
(every float field, raveled) and ``head`` (per field its offset and shape, then every int
field). :func:`pack` builds them from a NamedTuple; the formulation's compiled ``unpack``
reads the fields back (views, no copy) with :func:`unpack_as`, which takes each field's
dimensions from the NamedTuple's annotations (:data:`F1` ... :data:`I2`); the same function
gives the same views in Python.

The kernels that take the data are compiled without numba's reference counting
(``_nrt=False``): they allocate nothing (numba refuses to compile an allocation there),
and with counting every inlined helper that receives the NamedTuple would increment and
decrement the count of each of its arrays (measured: the primal stage rate 3.5 times
slower at n = 21).
"""

from __future__ import annotations

from typing import Annotated, get_type_hints

import numpy as np
from numba import njit
from numba.extending import overload

from ....groups.kernels_numba import normalize_rotations
from ....integrators.engine import CompiledProblem, EngineKernels
from .band import max_window_norm

_HW = 5  # head entries per field: offset, then up to four dimensions

#: Field annotations of the kernels' NamedTuples: float arrays of 1 to 4 dimensions, int
#: arrays of 1 or 2 (``float``, ``int`` and ``bool`` for scalars).
F1, F2, F3, F4 = (Annotated[np.ndarray, f"f{k}"] for k in range(1, 5))
I1, I2 = (Annotated[np.ndarray, f"i{k}"] for k in range(1, 3))


def c64(a):
    """``a`` as a C-contiguous float64 array: the only layout the kernels are compiled for
    (another layout would compile a second specialization of every kernel it reaches)."""
    return np.ascontiguousarray(a, dtype=np.float64)


def _is_int(a) -> bool:
    return np.asarray(a).dtype.kind in "iub"


def pack(data) -> tuple[np.ndarray, np.ndarray]:
    """``(flat, head)`` of a NamedTuple of arrays and scalars (ints and bools go to ``head``)."""
    nf = len(data)
    fsize = sum(np.size(a) for a in data if not _is_int(a))
    isize = sum(np.size(a) for a in data if _is_int(a))
    flat = np.zeros(fsize)
    head = np.zeros(_HW * nf + isize, dtype=np.int64)
    fpos, ipos = 0, _HW * nf
    for k, (a, r) in enumerate(zip(data, field_readers(type(data)))):
        a = np.asarray(a)
        if a.ndim != (int(r[1:]) if r[1:].isdigit() else 0) or _is_int(a) != (r[0] != "f"):
            raise ValueError(f"{type(data).__name__}.{data._fields[k]}: a {a.dtype} array of "
                             f"{a.ndim} dimensions, annotated {r}")
        head[_HW * k + 1:_HW * k + 1 + a.ndim] = a.shape
        if _is_int(a):
            head[_HW * k] = ipos
            head[ipos:ipos + a.size] = a.ravel()
            ipos += a.size
        else:
            head[_HW * k] = fpos
            flat[fpos:fpos + a.size] = a.ravel()
            fpos += a.size
    return flat, head


@njit(cache=True, inline="always")
def f1(flat, head, k):
    o = head[_HW * k]
    return flat[o:o + head[_HW * k + 1]]


@njit(cache=True, inline="always")
def f2(flat, head, k):
    o, s0, s1 = head[_HW * k], head[_HW * k + 1], head[_HW * k + 2]
    return flat[o:o + s0 * s1].reshape((s0, s1))


@njit(cache=True, inline="always")
def f3(flat, head, k):
    o, s0, s1, s2 = head[_HW * k], head[_HW * k + 1], head[_HW * k + 2], head[_HW * k + 3]
    return flat[o:o + s0 * s1 * s2].reshape((s0, s1, s2))


@njit(cache=True, inline="always")
def f4(flat, head, k):
    o, s0, s1 = head[_HW * k], head[_HW * k + 1], head[_HW * k + 2]
    s2, s3 = head[_HW * k + 3], head[_HW * k + 4]
    return flat[o:o + s0 * s1 * s2 * s3].reshape((s0, s1, s2, s3))


@njit(cache=True, inline="always")
def fs(flat, head, k):
    return flat[head[_HW * k]]


@njit(cache=True, inline="always")
def i1(flat, head, k):
    return f1(head, head, k)


@njit(cache=True, inline="always")
def i2(flat, head, k):
    return f2(head, head, k)


@njit(cache=True, inline="always")
def is_(flat, head, k):
    return fs(head, head, k)


@njit(cache=True, inline="always")
def bs(flat, head, k):
    return is_(flat, head, k) != 0


_READERS = {"f1": f1, "f2": f2, "f3": f3, "f4": f4, "i1": i1, "i2": i2, "fs": fs, "is_": is_, "bs": bs}


def field_readers(cls) -> tuple[str, ...]:
    """The reader of each field of the NamedTuple ``cls`` (:func:`f1` ... :func:`bs`),
    from its annotations (:data:`F1` ... :data:`I2`, ``float``, ``int``, ``bool``)."""
    hints = get_type_hints(cls, include_extras=True)
    scalars = {float: "fs", int: "is_", bool: "bs"}
    out = []
    for name in cls._fields:
        hint = hints[name]
        meta = getattr(hint, "__metadata__", None)
        if meta is None and hint not in scalars:
            raise TypeError(f"{cls.__name__}.{name}: annotate with F1..F4, I1, I2, float, int or bool")
        out.append(meta[0] if meta else scalars[hint])
    return tuple(out)


def unpack_as(cls, flat, head):
    """The NamedTuple ``cls`` of views into :func:`pack`'s ``flat`` and ``head`` (in
    compiled code and in Python; the fields' dimensions come from ``cls``'s annotations)."""
    out = []
    for k, r in enumerate(field_readers(cls)):
        o = int(head[_HW * k])
        if not r[1:].isdigit():
            out.append({"fs": float, "is_": int, "bs": bool}[r]((flat if r == "fs" else head)[o]))
        else:
            shape = tuple(int(x) for x in head[_HW * k + 1:_HW * k + 1 + int(r[1])])
            out.append((flat if r[0] == "f" else head)[o:o + int(np.prod(shape))].reshape(shape))
    return cls(*out)


@overload(unpack_as)
def _unpack_as(cls, flat, head):
    """Compiled :func:`unpack_as`: the reader calls of ``cls``'s fields written out once per
    NamedTuple class (numba types the class's fields from them)."""
    pycls = cls.instance_class
    args = ", ".join(f"{r}(flat, head, {k})" for k, r in enumerate(field_readers(pycls)))
    scope = dict(_READERS, _cls=pycls)
    exec(f"def impl(cls, flat, head):\n    return _cls({args})\n", scope)
    return scope["impl"]


@njit(cache=True, _nrt=False)
def call_angle(u, band, j0):
    """Largest ``|Theta|`` at the points of the increment ``u`` (:func:`~.band.max_window_norm`)."""
    return max_window_norm(band, j0, u[1])


# ====================================================================== engine kernels
# The state is a tuple of arrays (c, v, w, R, K[, K_s]); increments are flat (12 n) and
# seen as (4, n, 3).
@njit(cache=True, inline="always")
def engine_end_step(data, y):
    """Newton-Schulz step on the rotations of ``y`` (its fourth array), in place."""
    normalize_rotations(y[3])


@njit(cache=True, inline="always")
def engine_scale(data, y, out):
    """``|c|`` on the position component (the state's first array), ones elsewhere."""
    c = y[0]
    n = c.shape[0]
    for i in range(n):
        for d in range(3):
            out[3 * i + d] = abs(c[i, d])
    for j in range(3 * n, out.shape[0]):
        out[j] = 1.0


@njit(cache=True, inline="always")
def engine_increment_view(data, u):
    """The flat increment ``(12 n,)`` as ``(4, n, 3)``."""
    return u.reshape((4, u.shape[0] // 12, 3))


@njit(cache=True, inline="always")
def engine_increment_views(data, K):
    """Rows of flat increments ``(k, 12 n)`` as ``(k, 4, n, 3)``."""
    return K.reshape((K.shape[0], 4, K.shape[1] // 12, 3))


@njit(cache=True, inline="always")
def _new_state5(data, y):
    return (np.empty_like(y[0]), np.empty_like(y[1]), np.empty_like(y[2]), np.empty_like(y[3]),
            np.empty_like(y[4]))


@njit(cache=True, inline="always")
def _new_state6(data, y):
    return (np.empty_like(y[0]), np.empty_like(y[1]), np.empty_like(y[2]), np.empty_like(y[3]),
            np.empty_like(y[4]), np.empty_like(y[5]))


@njit(cache=True, inline="always")
def _copy(src, dst):
    """``dst <- src`` for C-contiguous arrays of one shape, through flat views, as a loop: a
    slice assignment compiles numba's shape check with its error-message formatting."""
    s, d = src.reshape(src.size), dst.reshape(dst.size)
    for j in range(s.shape[0]):
        d[j] = s[j]


@njit(cache=True, inline="always")
def _copy_state5(data, src, dst):
    _copy(src[0], dst[0])
    _copy(src[1], dst[1])
    _copy(src[2], dst[2])
    _copy(src[3], dst[3])
    _copy(src[4], dst[4])


@njit(cache=True, inline="always")
def _copy_state6(data, src, dst):
    _copy_state5(data, src, dst)
    _copy(src[5], dst[5])


@njit(cache=True, inline="always")
def engine_angle(data, u):
    """Largest ``|Theta|`` at the points of the increment ``u`` (any formulation's data)."""
    return max_window_norm(data[0].band, data[0].j0, u[1])


def engine_kernels(name: str, rate, action, fields: int) -> EngineKernels:
    """The compiled engine's kernels of a beam formulation whose state has ``fields``
    arrays (5 or 6)."""
    new_state, copy_state = {5: (_new_state5, _copy_state5), 6: (_new_state6, _copy_state6)}[fields]
    return EngineKernels(name, rate, action, engine_angle, engine_scale, end_step=engine_end_step,
                         new_state=new_state, copy_state=copy_state, increment_view=engine_increment_view,
                         increment_views=engine_increment_views)


class KernelSet:
    """Named data and thin wrappers of one beam formulation's compiled kernels.

    A subclass sets :attr:`data_cls` and :attr:`fields` (the state's arrays, in the
    kernels' order) and implements :meth:`kernels`: ``(action, rates, engine kernels)``
    called as ``action(u, *y, *y_out, flat, head)`` and ``rates(*y, u, out, flat, head) ->
    power``. The rotation angle of an increment is the same for every formulation
    (:func:`call_angle` on the data's ``band`` and ``j0``).
    """

    data_cls: type = tuple
    fields: tuple[str, ...] = ()

    def __init__(self, data, table, n: int):
        self._table, self.n = table, n
        self.flat, self.head = pack(data)
        self._pw = np.zeros(1)  # the power of the last increment_rate call
        self._zero = np.zeros((4, n, 3))
        self.__setstate__(self.__dict__)

    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if k != "data"}

    def __setstate__(self, state):
        self.__dict__.update(state)
        #: the kernels' data as a NamedTuple of views into ``flat`` and ``head``
        self.data = unpack_as(self.data_cls, self.flat, self.head)

    def kernels(self) -> tuple:
        raise NotImplementedError

    def _state(self, y) -> tuple:
        return tuple(c64(getattr(y, f)) for f in self.fields)

    def action(self, u, y, state_cls):
        ys = self._state(y)
        out = [np.empty_like(a) for a in ys]
        self.kernels()[0](c64(u), *ys, *out, self.flat, self.head)
        return state_cls(*out)

    def increment_rate(self, t, y, u):
        self._table.set(self.data.loads, t)
        out = np.empty((4, self.n, 3))
        self._pw[0] = self.kernels()[1](*self._state(y), c64(u), out, self.flat, self.head)
        return out

    def vector_field(self, t, y):
        return self.increment_rate(t, y, self._zero)

    def rotation_angle(self, u) -> float:
        return float(call_angle(c64(u), self.data.band, self.data.j0))

    def compiled_problem(self, state_cls):
        """What the compiled engine needs (:class:`~liegroup_int.integrators.engine.CompiledProblem`),
        or ``None`` when a load profile cannot be evaluated in compiled code. The engine's
        data hold a private copy of the flat data (stage loads and work arrays)."""
        enc = self._table.encoded()
        if enc is None:
            return None
        n, fields = self.n, self.fields

        def pack_state(y):
            return tuple(c64(getattr(y, f)) for f in fields)

        def unpack_state(arrays):
            return state_cls(*arrays)

        data = unpack_as(self.data_cls, self.flat.copy(), self.head)
        return CompiledProblem(self.kernels()[2], (data, *enc), lambda packed: 12 * n, pack_state, unpack_state)
