"""PNG plots of a run: histories against time and deformed beam shapes."""

from __future__ import annotations

from pathlib import Path

import numpy as np


class _Figures:
    """The part of pyplot these plots use (``subplots``, ``figure``, ``get_cmap``,
    ``close``), on :class:`matplotlib.figure.Figure` directly: without pyplot's import (0.3
    to 0.5 s of a short run) and its global figure registry. A figure made this way prints
    through the Agg canvas that ``savefig`` picks for the file's format."""

    @staticmethod
    def figure(figsize=None):
        from matplotlib.figure import Figure

        return Figure(figsize=figsize)

    @classmethod
    def subplots(cls, nrows: int = 1, ncols: int = 1, *, figsize=None, **kw):
        fig = cls.figure(figsize)
        return fig, fig.subplots(nrows, ncols, **kw)

    @staticmethod
    def get_cmap(name: str):
        import matplotlib

        return matplotlib.colormaps[name]

    @staticmethod
    def close(fig) -> None:
        """Nothing to release: no registry holds the figure."""


def _figures() -> type[_Figures]:
    return _Figures


def preload() -> None:
    """Import what drawing needs and draw a small figure with text into memory (the Agg
    canvas, the ticker, the PNG writer, the font file): what a run's first plot would
    otherwise spend (about 0.4 s). The runner calls it in a thread while it integrates (the
    compiled loops release the GIL), so a short run's plots cost only their drawing."""
    import io

    from matplotlib.ticker import LogFormatter

    fig, ax = _Figures.subplots(figsize=(1.0, 1.0))
    ax.plot([0.0, 1.0], [1e-3, 1.0])
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(LogFormatter())
    ax.set_title("t")
    fig.savefig(io.BytesIO(), format="png", dpi=20)


def save_figure(fig, path: Path, title: str = "", hspace: float = 0.12, wspace: float = 0.3) -> Path:
    """Title, margins, PNG/PDF at 110 dpi, and the figure closed.

    The margins are fixed in inches (room for tick labels and axis labels of the size these
    figures use), not measured: ``tight_layout`` draws the figure once more to measure it and
    took 60-80 % of a run's plotting time."""
    if title:
        fig.suptitle(title)
    w, h = fig.get_size_inches()
    top = 0.45 + (0.3 if any(ax.get_title() for ax in fig.axes) else 0.0)  # room for axes titles
    fig.subplots_adjust(left=0.85 / w, right=1 - 0.15 / w, bottom=0.5 / h, top=1 - top / h, hspace=hspace,
                        wspace=wspace)
    fig.savefig(path, dpi=110)
    return Path(path)


#: Axis labels with units of the recorded quantities (history column groups).
UNITS = {"tip": "tip position [m]", "work": "work of the loads [J]",
         "energy_balance": "E_kin + E_strain - W - E0 [J]", "kinetic": "kinetic energy [J]",
         "strain": "strain energy [J]", "momentum": "momentum [kg m/s]", "angular_momentum": "angular momentum [N m s]",
         "orth_error": "|R^T R - I| [-]", "omega_body": "body angular velocity [rad/s]", "R": "R [-]"}
UNIT_OF = {"energy": "J", "casimir": "-"}


def plot_history(history: dict[str, np.ndarray], path: Path, title: str = "", energy_scale: float = 0.0,
                 balance_tolerance: float = 0.0) -> Path:
    """One panel per group of columns (``tip_*`` together, others alone), against ``t``.

    Energy-like columns are shown as the change from their initial value. With an
    ``energy_scale`` (the run's largest ``|E|``, ``|W|``: summary.json
    ``energy_balance.energy_scale``), the energy balance ``E - W - E0`` (load work included)
    is shown relative to it on a log scale, with the guard's ``balance_tolerance``.
    """
    from matplotlib.ticker import LogFormatter

    plt = _figures()
    t = history["t"]
    groups: dict[str, list[str]] = {}
    for name in history:
        if name == "t":
            continue
        key = name.rsplit("_", 1)[0] if name.rsplit("_", 1)[-1] in ("x", "y", "z") else name
        groups.setdefault(key, []).append(name)
    fig, axes = plt.subplots(len(groups), 1, figsize=(7, 2.2 * len(groups) + 0.6), sharex=True, squeeze=False)
    for ax, (key, cols) in zip(axes[:, 0], groups.items()):
        label = UNITS.get(key, key)
        if key == "energy_balance" and energy_scale > 0:
            rel = np.abs(history[key]) / energy_scale
            shown = rel > 0
            ax.semilogy(t[shown], rel[shown], label=f"|E - W - E0| / {energy_scale:.3g} J")
            ax.yaxis.set_major_formatter(LogFormatter())  # plain 1e-05 labels: no mathtext to lay out
            if balance_tolerance > 0:
                ax.axhline(balance_tolerance, color="C3", ls="--", lw=1, label=f"guard ({balance_tolerance:g})")
            ax.set_ylabel("energy balance / energy scale [-]", fontsize=8)
            ax.legend(loc="best", fontsize=8)
            ax.grid(alpha=0.3, which="both")
            continue
        for c in cols:
            y = history[c]
            if key in ("energy", "casimir"):
                ax.plot(t, y - y[0], label=f"{c} - {c}(0)")
                label = f"{key} - {key}(0) [{UNIT_OF.get(key, '-')}]"
            else:
                ax.plot(t, y, label=c)
        ax.set_ylabel(label, fontsize=8)
        ax.legend(loc="best", fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("t [s]")
    return save_figure(fig, path, title)


def plot_shapes(times: np.ndarray, shapes: np.ndarray, path: Path, n_shapes: int = 6, title: str = "",
                bodies=(None, None)) -> Path:
    """Deformed centrelines at ``n_shapes`` times spread over the run, in 3-D and in
    the two projections with the largest extent; a motion that stays in a coordinate plane
    (its extent across it below 1e-9 of the largest) in that plane only.

    Parameters
    ----------
    times : (m,) array
    shapes : (m, k, 3) array
        Centreline points at each time (NaN points break the line, between the members of
        a frame).
    bodies : ((m, b, 3) array, (m, b, 3) array) or (None, None)
        The rigid bodies' joint points and centres of mass: a dot at each centre, joined to
        its point.
    """
    plt = _figures()
    idx = np.unique(np.linspace(0, len(times) - 1, min(n_shapes, len(times))).round().astype(int))
    pts = shapes[idx]
    joint, centre = bodies
    flat = shapes.reshape(-1, 3) if centre is None else np.concatenate([shapes.reshape(-1, 3), centre.reshape(-1, 3)])
    ext = np.nanmax(flat, axis=0) - np.nanmin(flat, axis=0)
    a, b = sorted(np.argsort(ext)[-2:])
    planar = bool(np.min(ext) <= 1e-9 * np.max(ext))
    fig = plt.figure(figsize=(7, 4.5) if planar else (11, 4.5))
    ax3 = None if planar else fig.add_subplot(1, 2, 1, projection="3d")
    ax2 = fig.add_subplot(1, 1, 1) if planar else fig.add_subplot(1, 2, 2)
    cmap = plt.get_cmap("viridis")
    for j, (i, p) in enumerate(zip(idx, pts)):
        col = cmap(j / max(1, len(idx) - 1))
        label = f"t = {times[i]:.4g} s"
        if ax3 is not None:
            ax3.plot(p[:, 0], p[:, 1], p[:, 2], color=col, label=label)
        ax2.plot(p[:, a], p[:, b], color=col, label=label)
        if centre is not None:
            _draw_bodies(ax2, ax3, joint[i], centre[i], (a, b), col)
    (ax3 or ax2).legend(fontsize=7, loc="upper left" if ax3 else "best")
    if ax3 is not None:
        ax3.set_xlabel("x1"), ax3.set_ylabel("x2"), ax3.set_zlabel("x3")
    ax2.set_xlabel(f"x{a + 1} [m]"), ax2.set_ylabel(f"x{b + 1} [m]")
    ax2.set_aspect("equal", adjustable="datalim")
    ax2.grid(alpha=0.3)
    return save_figure(fig, path, title)


def _draw_bodies(ax2, ax3, joint: np.ndarray, centre: np.ndarray, plane: tuple, col) -> None:
    """Each body ``(b, 3)`` as a dot at its centre joined to its joint point, in the 3-D axes
    (if any) and the projection on the coordinates ``plane``."""
    a, b = plane
    for jp, cp in zip(joint, centre):
        seg = np.array([jp, cp])
        if ax3 is not None:
            ax3.plot(seg[:, 0], seg[:, 1], seg[:, 2], color=col, lw=0.8, marker="o", markevery=[1], ms=4)
        ax2.plot(seg[:, a], seg[:, b], color=col, lw=0.8, marker="o", markevery=[1], ms=4)


def plot_run(run_dir: Path, times=None, formats=("png", "pdf")) -> list[Path]:
    """Plots of a finished (or interrupted) run directory.

    Writes ``plot_history.{fmt}`` from ``history.csv`` and, when ``shapes.npz`` exists,
    ``plot_shapes.{fmt}`` at the requested ``times`` (nearest recorded output times; six
    spread over the run by default); for a study directory (``study.csv``), the
    convergence and work-precision figures are re-drawn by :mod:`liegroup_int.studies`.

    Returns
    -------
    list of Path
        Files written.
    """
    from .history import read_history

    run_dir = Path(run_dir)
    made: list[Path] = []
    hist = run_dir / "history.csv"
    if not hist.exists():
        raise FileNotFoundError(f"{run_dir}: no history.csv (not a run directory)")
    data = read_history(hist)
    scale, tol = 0.0, 0.0
    summary = run_dir / "summary.json"
    if summary.exists():
        import json

        eb = json.loads(summary.read_text()).get("energy_balance") or {}
        scale, tol = float(eb.get("energy_scale") or 0.0), float(eb.get("tolerance") or 0.0)
    for fmt in formats:
        made.append(plot_history(data, run_dir / f"plot_history.{fmt}", title=run_dir.name, energy_scale=scale,
                                 balance_tolerance=tol))
    shapes = run_dir / "shapes.npz"
    if shapes.exists():
        with np.load(shapes) as z:
            t, line = z["t"], z["centreline"]
            bodies = tuple(z[k] if k in z.files else None for k in ("body_joint", "body_centre"))
        if times is not None:
            idx = np.unique([int(np.argmin(np.abs(t - x))) for x in times])
            t, line = t[idx], line[idx]
            bodies = tuple(b[idx] if b is not None else None for b in bodies)
            n = len(idx)
        else:
            n = 6
        for fmt in formats:
            made.append(plot_shapes(t, line, run_dir / f"plot_shapes.{fmt}", n_shapes=n, title=run_dir.name,
                                    bodies=bodies))
    return made
