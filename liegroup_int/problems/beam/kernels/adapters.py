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
gives the same views in Python. ``unpack`` is inlined into each entry and builds its views
directly (:func:`_view`), without reference counting: 0.3 us a call on the Galerkin data,
against 1.8 us as a separate function returning the NamedTuple.

The kernels that take the data are compiled without numba's reference counting
(``_nrt=False``): they allocate nothing (numba refuses to compile an allocation there),
and with counting every inlined helper that receives the NamedTuple would increment and
decrement the count of each of its arrays (measured: the primal stage rate 3.5 times
slower at n = 21).
"""

from __future__ import annotations

from typing import Annotated, get_type_hints

import numpy as np
from numba import njit, typeof
from numba.core import cgutils, types
from numba.core.imputils import impl_ret_borrowed
from numba.extending import intrinsic, overload
from numba.np.arrayobj import populate_array

from ....groups.kernels_numba import normalize_rotations
from ....integrators.engine import CompiledProblem, EngineKernels, FunctionValue
from .band import max_window_norm
from .profiles import set_loads

#: Where the engine's data (:meth:`KernelSet.compiled_problem`) hold the packed data, the
#: stage loads (a view into ``flat``) and their table (:func:`~.profiles.set_loads`), the
#: basis windows, and the formulation's entries ``rates`` and ``action``.
FLAT, HEAD, LOADS, ROWS, VECS, PROFILES, BAND, J0, RATES, ACTION = range(10)

#: The Galerkin stage rate's ``kin``: without the rotational increment's rate (the
#: leapfrog's kicks), with it from the increment, or with the values at the points that the
#: action has just computed from the same increment (the engine's stages after the first).
KIN_NONE, KIN_COMPUTE, KIN_FROM_ACTION = 0, 1, 2

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


@intrinsic
def _view(typingctx, arr, offset, shape):
    """The C-contiguous view of ``shape`` (a tuple of ints) into the 1-D array ``arr`` from
    ``offset`` on, built directly: no bounds or size checks (:func:`pack` laid the fields
    out), and no call into numba's reshape helper (about 15 ns a view)."""
    nd = len(shape)
    ret = types.Array(arr.dtype, nd, "C")

    def codegen(context, builder, sig, args):
        src = context.make_array(arr)(context, builder, value=args[0])
        dims = cgutils.unpack_tuple(builder, args[2], nd)
        itemsize = context.get_constant(types.intp, context.get_abi_sizeof(context.get_data_type(arr.dtype)))
        strides, acc = [None] * nd, itemsize
        for k in reversed(range(nd)):
            strides[k], acc = acc, builder.mul(acc, dims[k])
        out = context.make_array(ret)(context, builder)
        populate_array(out, data=builder.gep(src.data, [args[1]]), shape=dims, strides=strides,
                       itemsize=itemsize, meminfo=src.meminfo, parent=src.parent)
        return impl_ret_borrowed(context, builder, ret, out._getvalue())

    return ret(arr, types.intp, types.UniTuple(types.intp, nd)), codegen


def field_readers(cls) -> tuple[str, ...]:
    """The reader of each field of the NamedTuple ``cls``: ``"f1"`` ... ``"f4"`` (float
    arrays), ``"i1"``, ``"i2"`` (int arrays), ``"fs"``, ``"is_"``, ``"bs"`` (scalars), from
    its annotations (:data:`F1` ... :data:`I2`, ``float``, ``int``, ``bool``)."""
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


def _reader_expression(r: str, k: int) -> str:
    """The expression reading field ``k`` with the reader ``r`` (:func:`field_readers`),
    written out: ``_view`` calls and indexing only (typing 70 inlined reader calls took
    about 1 s more per entry)."""
    o = _HW * k
    if not r[1:].isdigit():
        return {"fs": f"flat[head[{o}]]", "is_": f"head[head[{o}]]", "bs": f"head[head[{o}]] != 0"}[r]
    dims = "".join(f"head[{o + 1 + d}], " for d in range(int(r[1])))
    return f"_view({'flat' if r[0] == 'f' else 'head'}, head[{o}], ({dims}))"


@overload(unpack_as, inline="always")
def _unpack_as(cls, flat, head):
    """Compiled :func:`unpack_as`: the readers of ``cls``'s fields written out once per
    NamedTuple class (numba types the class's fields from them)."""
    pycls = cls.instance_class
    args = ", ".join(_reader_expression(r, k) for k, r in enumerate(field_readers(pycls)))
    scope = dict(_view=_view, _cls=pycls)
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
    """Largest ``|Theta|`` at the points of the increment ``u`` (any formulation)."""
    return max_window_norm(data[BAND], data[J0], u[1])


@njit(cache=True, inline="always")
def _rate5(data, t, y, u, out):
    set_loads(data[LOADS], data[ROWS], data[VECS], data[PROFILES], t)
    return data[RATES](y[0], y[1], y[2], y[3], y[4], u, out, data[FLAT], data[HEAD], KIN_COMPUTE)


@njit(cache=True, inline="always")
def _staged_rate5(data, t, y, u, out):
    """The stage rate right after the action from the same increment: the rotational
    increment's values at the points are those the action left in the data."""
    set_loads(data[LOADS], data[ROWS], data[VECS], data[PROFILES], t)
    return data[RATES](y[0], y[1], y[2], y[3], y[4], u, out, data[FLAT], data[HEAD], KIN_FROM_ACTION)


@njit(cache=True, inline="always")
def _rate6(data, t, y, u, out):
    set_loads(data[LOADS], data[ROWS], data[VECS], data[PROFILES], t)
    return data[RATES](y[0], y[1], y[2], y[3], y[4], y[5], u, out, data[FLAT], data[HEAD])


@njit(cache=True, inline="always")
def _action5(data, u, y0, y1):
    data[ACTION](u, y0[0], y0[1], y0[2], y0[3], y0[4], y1[0], y1[1], y1[2], y1[3], y1[4], data[FLAT], data[HEAD])


@njit(cache=True, inline="always")
def _action6(data, u, y0, y1):
    data[ACTION](u, y0[0], y0[1], y0[2], y0[3], y0[4], y0[5], y1[0], y1[1], y1[2], y1[3], y1[4], y1[5],
                 data[FLAT], data[HEAD])


def engine_kernels(name: str, fields: int) -> EngineKernels:
    """The compiled engine's kernels of a beam formulation whose state has ``fields``
    arrays: 5, the Galerkin formulation's, or 6, the collocation's. They call the
    formulation's entries from Python (:meth:`KernelSet.kernels`: ``rates(*y, u, out, flat,
    head, *rate_args)``, ``action(u, *y, *y_out, flat, head)``), held in the data as
    first-class function values (:meth:`KernelSet.compiled_problem`). The loops are then
    compiled without the formulation's code (whose named data would make every loop
    compile for ~10 s), and the machine code they call is the one the Python side calls."""
    rate, staged, action, new_state, copy_state = {
        5: (_rate5, _staged_rate5, _action5, _new_state5, _copy_state5),
        6: (_rate6, None, _action6, _new_state6, _copy_state6)}[fields]
    return EngineKernels(name, rate, action, engine_angle, engine_scale, end_step=engine_end_step,
                         new_state=new_state, copy_state=copy_state, increment_view=engine_increment_view,
                         increment_views=engine_increment_views, staged_rate=staged)


def _function_types(fields: int, rate_args: tuple) -> tuple:
    """The first-class function types of the entries ``rates`` and ``action`` of a
    formulation whose state has ``fields`` arrays (:func:`engine_kernels`)."""
    a1, a2, a3 = (types.Array(types.float64, k, "C") for k in (1, 2, 3))
    state, packed = (a2, a2, a2, a3, a2, a2)[:fields], (a1, types.Array(types.int64, 1, "C"))
    extra = tuple(typeof(a) for a in rate_args)
    return (types.FunctionType(types.float64(*state, a3, a3, *packed, *extra)),
            types.FunctionType(types.none(a3, *state, *state, *packed)))


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
    rate_args: tuple = ()  # trailing arguments of the Python entry ``rates`` (Galerkin: ``kin = KIN_COMPUTE``)

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
        self._pw[0] = self.kernels()[1](*self._state(y), c64(u), out, self.flat, self.head, *self.rate_args)
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

        flat = self.flat.copy()
        d = unpack_as(self.data_cls, flat, self.head)
        action, rates, kernels = self.kernels()
        ftypes = _function_types(len(fields), self.rate_args)
        data = (flat, self.head, d.loads, *enc, d.band, d.j0, FunctionValue(rates, ftypes[0]),
                FunctionValue(action, ftypes[1]))
        return CompiledProblem(kernels, data, lambda packed: 12 * n, pack_state, unpack_state,
                               functions=((RATES, ftypes[0]), (ACTION, ftypes[1])))
