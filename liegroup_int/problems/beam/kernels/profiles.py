"""Time profiles of the beam's loads in compiled code, and the table of time-dependent loads.

A kernel reads the loads at the stage time from a ``(rows, 3)`` array ``loads``;
:class:`LoadTable` lists which rows are ``vector * profile(t)`` and rewrites them, in
Python (:meth:`LoadTable.set`) or in compiled code (:func:`set_loads` on the encoded
profiles of :meth:`LoadTable.encoded`).

Profile encoding (one row per profile, :func:`profile_row`): kind code, t_on, t_off, ramp,
number of table points m, table times (m), factors (m).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..model import Profile

PROFILE_KINDS = {"constant": 0, "step": 1, "ramp": 2, "smooth": 3, "table": 4, "raised_cosine": 5, "sine": 6}
_PR_KIND, _PR_ON, _PR_OFF, _PR_RAMP, _PR_M, _PR_TABLE = 0, 1, 2, 3, 4, 5


def profile_row(prof) -> np.ndarray | None:
    """Encode a :class:`~liegroup_int.problems.beam.model.Profile` for :func:`profile_value`.

    Returns ``None`` for anything the compiled evaluation does not reproduce: objects
    other than a ``Profile`` (a subclass may override ``__call__``), unknown kinds, and
    tables whose times are not finite and non-decreasing (``np.interp`` assumes sorted
    nodes; the driver then keeps the generic path, which calls the profile in Python).
    """
    if type(prof) is not Profile or prof.kind not in PROFILE_KINDS:
        return None
    table = np.asarray(prof.table, dtype=float).reshape(-1, 2) if prof.kind == "table" else np.zeros((0, 2))
    tt, ff = table[:, 0], table[:, 1]
    if prof.kind == "table" and not (np.all(np.isfinite(tt)) and np.all(np.diff(tt) >= 0)):
        return None
    head = [PROFILE_KINDS[prof.kind], prof.t_on, prof.t_off, prof.ramp, len(tt)]
    return np.concatenate([np.asarray(head, dtype=float), tt, ff])


class LoadTable:
    """The time-dependent rows of a kernel's ``loads`` array: ``loads[row] = vec * prof(t)``."""

    def __init__(self):
        self.rows: list[int] = []
        self.vecs: list[np.ndarray] = []
        self.profiles: list = []
        self._t = None
        self._enc = None

    def add(self, row: int, vec, prof) -> None:
        self.rows.append(int(row))
        self.vecs.append(np.asarray(vec, dtype=float).reshape(3))
        self.profiles.append(prof)

    def add_or_fix(self, loads: np.ndarray, row: int, vec, prof) -> None:
        """A row: written once here when ``prof`` is constant, else listed (:meth:`add`)."""
        if prof.is_constant:
            loads[row] = np.asarray(vec, dtype=float) * prof(0.0)
        else:
            self.add(row, vec, prof)

    def set(self, loads: np.ndarray, t: float) -> None:
        """The rows at ``t`` (once per distinct time): by :func:`set_loads` when every
        profile is encodable, so that the compiled engine's stage loads are bitwise the
        same, else by calling the profiles."""
        if t == self._t or not self.rows:
            return
        enc = self.encoded()
        if enc is not None:
            set_loads(loads, *enc, float(t))
        else:
            for r, vec, prof in zip(self.rows, self.vecs, self.profiles):
                loads[r] = vec * prof(t)
        self._t = t

    def encoded(self):
        """``(rows (k,), vecs (k, 3), profiles (k, width))`` for :func:`set_loads`, or
        ``None`` when a profile cannot be evaluated in compiled code."""
        if self._enc is None or self._enc[0] != len(self.rows):
            self._enc = (len(self.rows), self._encode())
        return self._enc[1]

    def _encode(self):
        enc = [profile_row(p) for p in self.profiles]
        if any(r is None for r in enc):
            return None
        k = len(enc)
        table = np.zeros((k, max((r.size for r in enc), default=_PR_TABLE)))
        for j, r in enumerate(enc):
            table[j, :r.size] = r
        return (np.array(self.rows, dtype=np.int64).reshape(k), np.array(self.vecs, dtype=float).reshape(k, 3),
                table)

    def __getstate__(self):
        return {**self.__dict__, "_t": None, "_enc": None}


@njit(cache=True)
def _interp(t, row):
    """``np.interp(t, tt, ff)`` for the (non-decreasing) table of a profile row, with
    NumPy's branch logic: ends held constant, the last node ``<= t`` starts the segment,
    exact hits return the node value."""
    m = int(row[_PR_M])
    tt, ff = row[_PR_TABLE:_PR_TABLE + m], row[_PR_TABLE + m:_PR_TABLE + 2 * m]
    if t > tt[m - 1]:
        return ff[m - 1]
    if t < tt[0]:
        return ff[0]
    j = 0
    while j + 1 < m and t >= tt[j + 1]:
        j += 1
    if j == m - 1 or tt[j] == t:
        return ff[j]
    slope = (ff[j + 1] - ff[j]) / (tt[j + 1] - tt[j])
    out = slope * (t - tt[j]) + ff[j]
    if out != out:  # NaN one way: NumPy tries the other end of the segment
        out = slope * (t - tt[j + 1]) + ff[j + 1]
        if out != out and ff[j] == ff[j + 1]:
            out = ff[j]
    return out


@njit(cache=True)
def profile_value(row, t):
    """:meth:`liegroup_int.problems.beam.model.Profile.__call__` on an encoded row."""
    kind = int(row[_PR_KIND])
    if kind == 0:
        return 1.0
    if kind == 4:
        return _interp(t, row)
    if t < row[_PR_ON] or t >= row[_PR_OFF]:
        return 0.0
    if kind == 1:
        return 1.0
    if kind == 6:
        return math.sin(2.0 * math.pi * (t - row[_PR_ON]) / row[_PR_RAMP])
    if kind == 5:
        y = (t - row[_PR_ON]) / row[_PR_RAMP]
        return 1.0 - math.cos(2.0 * math.pi * y) if y < 1.0 else 0.0
    x = min(1.0, (t - row[_PR_ON]) / row[_PR_RAMP])
    if kind == 2:
        return x
    s = math.sin(0.5 * math.pi * x)
    return s * s


@njit(cache=True)
def set_loads(loads, rows, vecs, profiles, t):
    """``loads[rows[k]] = vecs[k] * profile_k(t)`` (what :meth:`LoadTable.set` does in
    Python)."""
    for k in range(rows.shape[0]):
        f = profile_value(profiles[k], t)
        for d in range(3):
            loads[rows[k], d] = vecs[k, d] * f
