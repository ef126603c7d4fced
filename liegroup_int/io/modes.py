"""Files of a modal analysis (``liegroup-int modes``): table, ParaView shapes, picture."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from .paraview import write_beam_vtu, write_pvd
from .plots import _figures, save_figure

#: Names of the displacement and rotation components, for the dominant-component label.
_COMPONENTS = ("u1", "u2", "u3", "theta1", "theta2", "theta3")


def dominant(displacement: np.ndarray, rotation: np.ndarray, length: float) -> str:
    """The displacement component with the largest amplitude along the curve (``u3`` for
    bending in the x1-x3 plane of a beam along x1, ``u1`` for its axial modes), or the
    rotation component for modes that hardly displace the curve (largest displacement below
    5 % of ``length`` times the largest rotation: ``theta1`` for torsion)."""
    d, r = np.max(np.abs(displacement), axis=0), np.max(np.abs(rotation), axis=0)
    if np.max(d) >= 0.05 * length * np.max(r):
        return _COMPONENTS[int(np.argmax(d))]
    return _COMPONENTS[3 + int(np.argmax(r))]


def write_modes_csv(path: Path, rows: list[dict]) -> Path:
    """``mode, freq_hz, damping_ratio, re_lambda, im_lambda, growing, dominant,
    rel_change_finer`` (the relative change of the frequency on the next finer mesh; empty:
    not estimated)."""
    fields = ["mode", "freq_hz", "damping_ratio", "re_lambda", "im_lambda", "growing", "dominant", "rel_change_finer"]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow({k: (repr(v) if isinstance(v, float) else v) for k, v in r.items() if k in fields})
    return Path(path)


def write_mode_shapes(out_dir: Path, shapes: list[tuple], stem: str = "mode") -> list[Path]:
    """One VTU per mode (reference curve with point data ``displacement`` and ``rotation``,
    normalized to a largest displacement of 1, or rotation when the mode has no
    displacement) and ``modes.pvd`` indexing them by mode number (ParaView's time slider
    steps through the modes; Warp By Vector on ``displacement`` shows each)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    entries, made = [], []
    for k, (points, disp, rot) in enumerate(shapes, start=1):
        path = write_beam_vtu(out_dir / f"{stem}_{k:02d}.vtu", points,
                              point_data={"displacement": disp, "rotation": rot})
        entries.append((float(k), path.name))
        made.append(path)
    made.append(write_pvd(out_dir / "modes.pvd", entries))
    return made


def real_shapes(shapes: list[tuple], freqs, rtol: float = 1e-6) -> list[tuple]:
    """Real, normalized mode shapes from complex ones ``(points, displacement, rotation)``.

    Each shape is turned so that its largest entry is real (the configuration part of an
    undamped mode is real up to a phase) and its real part kept (:func:`normalized`).
    Degenerate pairs (consecutive modes whose frequencies agree to ``rtol``, e.g. the two
    bending planes of a symmetric section) come from the eigensolver as arbitrary complex
    combinations of the two planes: each pair is recombined first, into the combination
    without displacement along the pair's second largest displacement component and the one
    without displacement along its largest, i.e. one plane each."""
    out = []
    f = np.asarray(freqs, dtype=float)
    i = 0
    while i < len(shapes):
        if i + 1 < len(shapes) and abs(f[i + 1] - f[i]) <= rtol * max(abs(f[i]), 1e-300):
            (p, d1, r1), (_, d2, r2) = shapes[i], shapes[i + 1]
            amp = np.max(np.abs(d1), axis=0) + np.max(np.abs(d2), axis=0)
            j1, j2 = np.argsort(amp)[-2:][::-1]
            for j in (j2, j1):  # the first mode has no j2 displacement, the second no j1
                _, _, vh = np.linalg.svd(np.stack([d1[:, j], d2[:, j]], axis=1))
                a, b = np.conj(vh[-1])
                out.append((p, *_real(a * d1 + b * d2, a * r1 + b * r2)))
            i += 2
            continue
        p, d, r = shapes[i]
        out.append((p, *_real(d, r)))
        i += 1
    return out


def _real(disp: np.ndarray, rot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    both = np.concatenate([np.ravel(disp), np.ravel(rot)])
    k = int(np.argmax(np.abs(both)))
    phase = abs(both[k]) / both[k] if both[k] != 0 else 1.0
    return normalized(np.real(disp * phase), np.real(rot * phase))


def normalized(disp: np.ndarray, rot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Scale a shape to a largest displacement of 1 (rotation, if it has no displacement)."""
    scale = float(np.max(np.linalg.norm(disp, axis=1)))
    if scale <= 1e-12 * max(1.0, float(np.max(np.linalg.norm(rot, axis=1)))):
        scale = float(np.max(np.linalg.norm(rot, axis=1))) or 1.0
    return disp / scale, rot / scale


def plot_modes(path: Path, shapes: list[tuple], labels: list[str], title: str = "", n_max: int = 6) -> Path:
    """The first ``n_max`` mode shapes: the reference curve and the displaced one (largest
    displacement a tenth of the curve's extent). A straight or plane curve moving in its
    plane, or straight and moving across it, is drawn in the plane of its longest extent and
    the mode's largest displacement across it; a plane frame moving out of its plane (a
    lateral buckling mode), or a space curve, in 3D. Torsional modes show their rotation
    amplitude along the curve."""
    plt = _figures()
    k = min(n_max, len(shapes))
    cols = min(3, k)
    rows = (k + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.2 * rows), squeeze=False)
    for ax in axes.ravel()[k:]:
        ax.set_visible(False)
    for ax, (points, disp, rot), label in zip(axes.ravel(), shapes[:k], labels[:k]):
        extent = float(np.max(np.ptp(points, axis=0))) or 1.0
        dmax = float(np.max(np.linalg.norm(disp, axis=1)))
        if dmax <= 1e-9 * float(np.max(np.linalg.norm(rot, axis=1)) * extent + 1e-300):
            _plot_rotation(ax, points, rot)
        elif _needs_3d(points, disp):
            ax = _plot_3d(fig, ax, points, points + 0.1 * extent / dmax * disp)
        else:
            _plot_planar(ax, points, disp, points + 0.1 * extent / dmax * disp)
        ax.set_title(label, fontsize=9)
        ax.grid(alpha=0.3)
    return save_figure(fig, path, title, hspace=0.55, wspace=0.4)


def _needs_3d(points: np.ndarray, disp: np.ndarray) -> bool:
    """The curve spans two or three axes (the second-longest extent over a tenth of the
    longest) and the mode moves along the third by more than a tenth of its largest
    displacement, or the curve spans all three axes."""
    ext = np.ptp(points, axis=0)
    order = np.argsort(ext)
    if ext[order[1]] <= 0.1 * ext[order[2]]:
        return False
    return bool(ext[order[0]] > 0.1 * ext[order[2]] or
                np.max(np.abs(disp[:, order[0]])) > 0.1 * np.max(np.abs(disp)))


def _plot_planar(ax, points: np.ndarray, disp: np.ndarray, moved: np.ndarray) -> None:
    """Reference and mode in the plane of the curve's longest extent and the mode's largest
    displacement across it (the second-longest extent for an axial mode)."""
    ext = np.ptp(points, axis=0)
    a = int(np.argmax(ext))
    across = np.max(np.abs(disp), axis=0) + 1e-9 * ext
    across[a] = -1.0
    b = int(np.argmax(across))
    if np.max(np.abs(disp[:, b])) < 1e-3 * np.max(np.abs(disp[:, a])):  # an axial mode
        b = int(np.argsort(ext)[-2])
    ax.plot(points[:, a], points[:, b], color="0.6", lw=1, label="reference")
    ax.plot(moved[:, a], moved[:, b], color="C0", lw=1.5, label="mode")
    ax.set_xlabel(f"x{a + 1} [m]", fontsize=8), ax.set_ylabel(f"x{b + 1} [m]", fontsize=8)
    ax.set_aspect("equal", adjustable="datalim")


def _plot_3d(fig, ax, points: np.ndarray, moved: np.ndarray):
    """Reference and mode on a 3D axes in the place of ``ax`` (returned), to scale but for an
    axis shorter than 0.4 of the longest, drawn at that length."""
    spec = ax.get_subplotspec()
    ax.remove()
    ax = fig.add_subplot(spec, projection="3d")
    ax.plot(*points.T, color="0.6", lw=1, label="reference")
    ax.plot(*moved.T, color="C0", lw=1.5, label="mode")
    both = np.vstack([points, moved])
    ax.set_box_aspect(np.maximum(np.ptp(both, axis=0), 0.4 * np.max(np.ptp(both, axis=0))))  # a flat axis stays readable
    for setter, name in ((ax.set_xlabel, "x1"), (ax.set_ylabel, "x2"), (ax.set_zlabel, "x3")):
        setter(f"{name} [m]", fontsize=7)
    ax.tick_params(labelsize=6)
    return ax


def _plot_rotation(ax, points: np.ndarray, rot: np.ndarray) -> None:
    """A torsional mode: its rotation amplitude along the curve."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    ax.plot(s, rot, lw=1.2)
    ax.set_xlabel("s [m]", fontsize=8), ax.set_ylabel("rotation [-]", fontsize=8)
