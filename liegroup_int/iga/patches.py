"""Several collocation patches joined at their ends: the space of a frame of beams.

By default the patches form a chain: patch ``k`` ends where patch ``k + 1`` starts; the two
end control values there are two unknowns (one per patch) that the beam plugin keeps equal
(a rigid joint, docs/theory.md section 13). An explicit list of joints between any two patch
ends makes any graph (T and X junctions, closed rings, trees); a joint of ``k`` ends is
``k - 1`` pairs to its first end, each ``"rigid"`` (equal position and rotation),
``"ball"`` (equal position, rotations free) or ``"hinge"`` (equal position, relative
rotation about an axis only). Every matrix is block-diagonal, one block per
patch, so the patches' interpolation, derivatives and ``M_c`` solve stay their own.

Global parameter: patch ``k`` covers ``u in [U_k, U_k+1]`` with ``U_k`` the fraction of the
total reference length before it (patches in the given order), so ``u`` runs over
``[0, 1]`` along all patches as for one patch (outputs at fractions of the length, shapes,
ParaView).
"""

from __future__ import annotations

import numpy as np

from .collocation import CollocationSpace
from .nurbs import NurbsCurve, insert_knots

__all__ = ["JOINT_KINDS", "PatchedSpace", "split_curve"]

#: Kinds of joint: equal positions and rotations, equal positions only, or equal positions
#: and rotations but for a turn about an axis.
JOINT_KINDS = ("rigid", "ball", "hinge")
#: Sides of a patch: its start (``u = 0``) and its end (``u = 1``).
SIDES = ("start", "end")


def _block_diag(blocks) -> np.ndarray:
    n = sum(b.shape[0] for b in blocks)
    out = np.zeros((n, n))
    i = 0
    for b in blocks:
        m = b.shape[0]
        out[i:i + m, i:i + m] = b
        i += m
    out.setflags(write=False)
    return out


def _cat(arrays) -> np.ndarray:
    out = np.concatenate([np.asarray(a) for a in arrays])
    out.setflags(write=False)
    return out


def _hinge_axes(kinds, axes) -> tuple:
    """The unit axis of each hinge pair (None for the other kinds)."""
    axes = tuple(axes) if axes is not None else (None,) * len(kinds)
    if len(axes) != len(kinds):
        raise ValueError(f"axes: one per joint ({len(kinds)}), got {len(axes)}")
    out = []
    for k, (kind, a) in enumerate(zip(kinds, axes)):
        if kind != "hinge":
            out.append(None)
            continue
        a = np.zeros(3) if a is None else np.asarray(a, dtype=float)
        norm = float(np.linalg.norm(a)) if a.shape == (3,) else 0.0
        if not (np.isfinite(norm) and norm > 0.0):
            raise ValueError(f"joint {k + 1}: a hinge needs a finite non-zero axis [x, y, z], got "
                             f"{np.asarray(a).tolist()}")
        out.append(a / norm)
    return tuple(out)


def _springs(n: int, springs) -> tuple:
    """``(stiffness, damping)`` of each pair, checked finite and ``>= 0``."""
    out = tuple((float(k), float(c)) for k, c in springs) if springs is not None else ((0.0, 0.0),) * n
    if len(out) != n:
        raise ValueError(f"springs: one (stiffness, damping) per joint ({n}), got {len(out)}")
    for i, kc in enumerate(out):
        if not all(np.isfinite(v) and v >= 0.0 for v in kc):
            raise ValueError(f"joint {i + 1}: spring stiffness and damping must be finite and >= 0, got {list(kc)}")
    return out


def split_curve(curve: NurbsCurve, u: float) -> tuple[NurbsCurve, NurbsCurve]:
    """The two pieces of a curve at parameter ``u`` in ``(0, 1)``, each parametrized over ``[0, 1]``.

    The knot ``u`` is raised to multiplicity ``p`` (exact insertion), which makes the
    control point there the curve's point ``c(u)``; the pieces share it.
    """
    u = float(u)
    if not 0.0 < u < 1.0:
        raise ValueError(f"split parameter must lie in (0, 1), got {u!r}")
    p = curve.degree
    have = int(np.sum(np.isclose(curve.knots, u, rtol=0.0, atol=1e-14)))
    fine = insert_knots(curve, [u] * (p - have)) if have < p else curve
    kv = np.asarray(fine.knots)
    k = int(np.searchsorted(kv, u - 1e-14))  # first of the p copies of u
    pw = fine.homogeneous()
    j = k - 1  # the control point at c(u)
    left_kv = np.concatenate([kv[: k + p], [u]]) / u
    right_kv = (np.concatenate([[u], kv[k:]]) - u) / (1.0 - u)
    left = NurbsCurve.from_homogeneous(p, np.clip(left_kv, 0.0, 1.0), pw[: j + 1])
    right = NurbsCurve.from_homogeneous(p, np.clip(right_kv, 0.0, 1.0), pw[j:])
    return left, right


class PatchedSpace:
    """Collocation spaces of patches joined end to start, as one space.

    Parameters
    ----------
    spaces : sequence of CollocationSpace
        The patches; without ``joints`` in chain order, patch ``k``'s end coinciding with
        patch ``k + 1``'s start (checked to ``1e-9`` of the total length).
    joints : sequence of ((int, str), (int, str)), optional
        Explicit joints instead of the chain: pairs of patch ends ``(patch, "start" | "end")``
        that coincide (checked per pair to ``1e-9`` of the total length). The second end of
        a pair is joined to the first; it may not be the second end of another pair nor the
        first end of one (a joint of ``k`` ends is ``k - 1`` pairs to one first end, so the
        joints form no redundant loop of constraints).
    kinds : sequence of str, optional
        Kind of each pair of ``joints``, one of :data:`JOINT_KINDS` (default all rigid).
    axes : sequence of (array_like (3,) or None), optional
        Hinge axis of each pair (spatial, reference configuration; non-zero for a
        ``"hinge"`` pair, ignored for the others).
    springs : sequence of (float, float), optional
        Rotational spring stiffness [N m/rad] and damper [N m s/rad] about the axis of each
        pair (``>= 0``; used at hinges only, default 0).

    Attributes
    ----------
    patches : tuple of CollocationSpace
    offsets : tuple of int
        First global row of each patch (``offsets[-1]`` = ``n_ctrl``).
    joints : tuple of (int, int)
        Global rows ``(a, b)`` of each joint pair (chain: the last row of patch ``k`` and
        the first of patch ``k + 1``).
    joint_ends : tuple of ((int, str), (int, str))
        The patch ends of each pair; ``joint_kinds``: their kinds (tuple of str);
        ``joint_axes``: the unit hinge axis of each pair, ``(3,)`` (None but at hinges);
        ``joint_springs``: ``(stiffness, damping)`` of each pair.
    chain : bool
        The patches form the implied chain (no explicit ``joints``).
    n_ctrl, degree : int
        Total number of control values; the largest degree.
    N0, N1, N2 : numpy.ndarray, shape (n, n)
        Block-diagonal collocation matrices.
    u_c, s_c : numpy.ndarray, shape (n,)
        Global parameter and reference arc length of the collocation points (each joint
        appears twice, once per patch).
    c0, c0_s, c0_ss, K0, K0_s : numpy.ndarray, shape (n, 3); R0 : shape (n, 3, 3)
        Reference geometry, patch by patch.
    length : float
    l_s_start, l_s_end : float
        Half spacing of the first and last collocation points of the chain.
    bandwidths : tuple of int
    """

    def __init__(self, spaces, joints=None, kinds=None, axes=None, springs=None) -> None:
        spaces = tuple(spaces)
        if len(spaces) < 1 or not all(isinstance(s, CollocationSpace) for s in spaces):
            raise ValueError("PatchedSpace needs one or more CollocationSpace patches")
        self.patches = spaces
        lengths = np.array([s.length for s in spaces])
        self.length = float(lengths.sum())
        sizes = [s.n_ctrl for s in spaces]
        self.offsets = tuple(int(v) for v in np.concatenate([[0], np.cumsum(sizes)]))
        self.n_ctrl = self.offsets[-1]
        self.degree = max(s.degree for s in spaces)
        self.chain = joints is None
        if self.chain:
            joints = [((k, "end"), (k + 1, "start")) for k in range(len(spaces) - 1)]
        self.joint_ends = tuple((tuple(a), tuple(b)) for a, b in joints)
        kinds = tuple(kinds) if kinds is not None else ("rigid",) * len(self.joint_ends)
        if len(kinds) != len(self.joint_ends) or any(k not in JOINT_KINDS for k in kinds):
            raise ValueError(f"kinds: one of {', '.join(JOINT_KINDS)} per joint ({len(self.joint_ends)}), "
                             f"got {list(kinds)}")
        self.joint_kinds = kinds
        self.joint_axes = _hinge_axes(kinds, axes)
        self.joint_springs = _springs(len(kinds), springs)
        self.joints = tuple((self.end_row(*a), self.end_row(*b)) for a, b in self.joint_ends)
        self._check_joints()
        self._u_edges = np.concatenate([[0.0], np.cumsum(lengths) / self.length])
        self._u_edges[-1] = 1.0
        s_edges = np.concatenate([[0.0], np.cumsum(lengths)])
        self.N0 = _block_diag([s.N0 for s in spaces])
        self.N1 = _block_diag([s.N1 for s in spaces])
        self.N2 = _block_diag([s.N2 for s in spaces])
        for name in ("c0", "c0_s", "c0_ss", "R0", "K0", "K0_s", "jac"):
            setattr(self, name, _cat([getattr(s, name) for s in spaces]))
        self.u_c = _cat([self._u_edges[k] + (self._u_edges[k + 1] - self._u_edges[k]) * np.asarray(s.u_c)
                         for k, s in enumerate(spaces)])
        self.s_c = _cat([s_edges[k] + np.asarray(s.s_c) for k, s in enumerate(spaces)])
        self.l_s_start, self.l_s_end = spaces[0].l_s_start, spaces[-1].l_s_end
        bw = [s.bandwidths for s in spaces]
        self.bandwidths = (max(b[0] for b in bw), max(b[1] for b in bw))
        self.control_points = _cat([s.curve.control_points for s in spaces])

    def end_row(self, patch: int, side: str) -> int:
        """Global control row of a patch end (``side`` "start" or "end")."""
        if not (0 <= int(patch) < len(self.patches)) or side not in SIDES:
            raise ValueError(f"joint end {(patch, side)!r}: expected (patch index < {len(self.patches)}, "
                             f"'start' or 'end')")
        return self.offsets[patch] if side == "start" else self.offsets[patch + 1] - 1

    def _check_joints(self) -> None:
        """Joined ends coincide; the pairs form stars (no end joined twice, no loop)."""
        firsts = {a for a, _ in self.joints}
        seen = set()
        for k, ((a, b), ends) in enumerate(zip(self.joints, self.joint_ends)):
            if b in seen or b in firsts or a == b:
                raise ValueError(f"joint {k + 1}: patch end {ends[1]!r} is joined twice; join each end to one "
                                 "first end")
            seen.add(b)
            pa, pb = self.c0_at(a), self.c0_at(b)
            gap = float(np.linalg.norm(pa - pb))
            if gap > 1e-9 * self.length:
                which = (f"patch {ends[0][0] + 1} ends at {np.round(pa, 6).tolist()} but patch {ends[1][0] + 1} "
                         f"starts at {np.round(pb, 6).tolist()}") if self.chain else (
                    f"patch end {ends[0]!r} at {np.round(pa, 6).tolist()} and {ends[1]!r} at "
                    f"{np.round(pb, 6).tolist()}")
                raise ValueError(f"{which} ({gap:.3g} apart): joined ends must coincide")

    def c0_at(self, row: int) -> np.ndarray:
        """Reference position of an end row (a patch's first or last control value), ``(3,)``."""
        k = int(np.searchsorted(self.offsets, row, side="right") - 1)
        sp = self.patches[k]
        return np.asarray(sp.c0[0] if row == self.offsets[k] else sp.c0[-1], dtype=float)

    # ------------------------------------------------------------------
    def solve(self, rhs) -> np.ndarray:
        """Solve ``M_c x = rhs`` patch by patch; ``rhs`` of shape ``(n,)`` or ``(n, m)``."""
        b = np.asarray(rhs, dtype=float)
        if b.shape[:1] != (self.n_ctrl,) or b.ndim > 2:
            raise ValueError(f"rhs must have shape ({self.n_ctrl},) or ({self.n_ctrl}, m), got {b.shape}")
        o = self.offsets
        return np.concatenate([s.solve(b[o[k]:o[k + 1]]) for k, s in enumerate(self.patches)])

    def _local(self, u):
        """Patch index and local parameter of global parameters ``u``, ``(m,)`` each."""
        u = np.atleast_1d(np.asarray(u, dtype=float))
        k = np.clip(np.searchsorted(self._u_edges, u, side="right") - 1, 0, len(self.patches) - 1)
        lo, hi = self._u_edges[k], self._u_edges[k + 1]
        return k, np.clip((u - lo) / (hi - lo), 0.0, 1.0)

    def _rows(self, u, per_patch) -> np.ndarray:
        k, ul = self._local(u)
        out = np.zeros(per_patch(0, ul[:1]).shape[:-2] + (len(ul), self.n_ctrl))
        for j in np.unique(k):
            sel = k == j
            o = self.offsets
            out[..., sel, o[j]:o[j + 1]] = per_patch(j, ul[sel])
        return out

    def point_matrix(self, u) -> np.ndarray:
        """Basis values at global parameters ``u``, ``(m, n_ctrl)``."""
        return self._rows(u, lambda j, ul: self.patches[j].point_matrix(ul))

    def basis_s(self, u) -> np.ndarray:
        """Basis and its first two arc-length derivatives at global parameters, ``(3, m, n_ctrl)``."""
        return self._rows(u, lambda j, ul: self.patches[j].basis_s(ul))

    def arc_length(self, u) -> np.ndarray:
        """Reference arc length at global parameters ``u``, ``(m,)``."""
        k, ul = self._local(u)
        s_edges = self._u_edges * self.length
        return np.array([s_edges[j] + float(self.patches[j].arc_length([x])[0]) for j, x in zip(k, ul)])

    def frame(self, u):
        """Reference frame, curvature and its derivative at global parameters ``u``."""
        k, ul = self._local(u)
        parts = [self.patches[j].frame([x]) for j, x in zip(k, ul)]
        return tuple(np.concatenate([p[i] for p in parts]) for i in range(3))
