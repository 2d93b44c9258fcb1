"""Report figures (matplotlib, Agg canvas, no pyplot state): arrays in, Figures out.

Every function takes what it plots, already in display units (mm, deg, N,
N·m), and returns a :class:`matplotlib.figure.Figure`; :func:`to_png` turns
one into PNG bytes. Nothing here computes model quantities.
"""
from __future__ import annotations

import io

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure


def new_figure(width: float, height: float, layout: str | None = "constrained") -> Figure:
    """A Figure of ``width`` × ``height`` inches on its own Agg canvas (no pyplot state).

    ``layout=None`` leaves the axes where the caller puts them (:func:`grid_axes`):
    the constrained layout measures every label twice when the figure is saved.
    """
    fig = Figure(figsize=(width, height), layout=layout)
    FigureCanvasAgg(fig)
    return fig


def grid_axes(fig: Figure, nrows: int, ncols: int, margins=(0.65, 0.1, 0.1, 0.5),
              gaps=(0.3, 0.5), **kwargs):
    """An ``nrows`` × ``ncols`` grid of axes at fixed distances in inches.

    ``margins`` are (left, right, top, bottom) and ``gaps`` (between columns, between
    rows), inches: room for the tick labels and an axis label of 7–8 pt; ``kwargs`` go
    to :meth:`matplotlib.figure.Figure.subplots` (``sharey=True``, …).
    """
    width, height = fig.get_size_inches()
    left, right, top, bottom = margins
    gap_x, gap_y = gaps
    axes_w = (width - left - right - (ncols - 1) * gap_x) / ncols
    axes_h = (height - top - bottom - (nrows - 1) * gap_y) / nrows
    return fig.subplots(nrows, ncols, squeeze=False, gridspec_kw=dict(
        left=left / width, right=1.0 - right / width, top=1.0 - top / height,
        bottom=bottom / height, wspace=gap_x / axes_w, hspace=gap_y / axes_h), **kwargs)


def plain_ticks(ax) -> None:
    """Small tick labels, no offset like "1e-13" above the axis, at most 5 per axis."""
    from matplotlib.ticker import MaxNLocator, ScalarFormatter

    for axis in (ax.xaxis, ax.yaxis):
        formatter = ScalarFormatter(useOffset=False)
        formatter.set_powerlimits((-3, 4))
        axis.set_major_formatter(formatter)
        axis.set_major_locator(MaxNLocator(5))
    ax.tick_params(labelsize=7)


def to_png(fig: Figure, dpi: int = 90) -> bytes:
    """PNG bytes of ``fig`` at ``dpi`` dots per inch."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def correlation_heatmap(names, correlation) -> Figure:
    """Heat map of a correlation matrix (F, F) in [−1, 1] of the F parameters ``names``."""
    c = np.asarray(correlation, float)
    f = len(names)
    size = min(max(4.0, 0.18 * f + 2.0), 16.0)
    fig = new_figure(size + 1.0, size)
    ax = fig.add_subplot()
    im = ax.imshow(c, cmap="RdBu_r", vmin=-1.0, vmax=1.0, interpolation="nearest")
    font = max(4.0, min(9.0, 300.0 / max(f, 1)))
    ax.set_xticks(range(f), names, rotation=90, fontsize=font)
    ax.set_yticks(range(f), names, fontsize=font)
    fig.colorbar(im, ax=ax, shrink=0.8, label="correlation")
    ax.set_title("correlation of the free parameters")
    return fig


def residual_scatter(norm_mm, columns, ncols: int = 4) -> Figure:
    """A grid of scatter plots (``ncols`` a row): the 3-D residual norm (K,) mm of each
    reading against each variable of ``columns``, (label with unit, values (K,))."""
    norm_mm = np.asarray(norm_mm, float)
    n = len(columns)
    nrows = max(1, -(-n // ncols))
    fig = new_figure(3.0 * ncols, 2.4 * nrows, layout=None)  # fixed margins: 0.3 s less
    axes = grid_axes(fig, nrows, ncols, sharey=True)
    for ax, (label, x) in zip(axes.flat, columns):
        ax.scatter(np.asarray(x, float), norm_mm, s=6, alpha=0.6, color="tab:blue")
        ax.set_xlabel(label, fontsize=8)
        plain_ticks(ax)
    for ax in axes[:, 0]:
        ax.set_ylabel("|residual| (mm)", fontsize=8)
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    return fig


def residual_bars(stats: dict, what: str) -> Figure:
    """RMS (per coordinate) and max 3-D residual per group, mm, as bars: ``stats`` group →
    ``{"rms_mm", "max_3d_mm", ...}``; ``what`` the groups are (``marker``, ``pose``)."""
    names = list(stats)
    x = np.arange(len(names))
    fig = new_figure(min(max(4.0, 0.3 * len(names) + 2.0), 16.0), 3.2)
    ax = fig.add_subplot()
    ax.bar(x - 0.2, [stats[k]["rms_mm"] for k in names], 0.4, label="RMS per coordinate")
    ax.bar(x + 0.2, [stats[k]["max_3d_mm"] for k in names], 0.4, label="max 3-D")
    step = -(-len(names) // 40)  # at most 40 labels: hundreds of poses would overlap
    ax.set_xticks(x[::step], names[::step], rotation=90 if len(names) > 12 else 0, fontsize=7)
    ax.set_xlabel(what if step == 1 else f"{what} (every {step}th labelled)")
    ax.set_ylabel("residual (mm)")
    ax.legend(fontsize=8)
    return fig


def joint_angle_chart(joint_names, q, lower, upper, units) -> Figure:
    """Joint positions ``q`` (M, N) of the chosen poses, deg (mm), one marker set per joint,
    the limits ``lower``, ``upper`` (N,) shaded where finite."""
    q = np.atleast_2d(np.asarray(q, float))
    m, n = q.shape
    fig = new_figure(max(5.0, 1.2 * n + 2.0), 4.0)
    ax = fig.add_subplot()
    for k in range(n):
        if np.isfinite(lower[k]) and np.isfinite(upper[k]):
            ax.fill_between([k - 0.4, k + 0.4], lower[k], upper[k], color="0.88",
                            label="joint limits" if k == 0 else None)
        offset = np.linspace(-0.25, 0.25, m) if m > 1 else np.zeros(1)
        ax.plot(k + offset, q[:, k], "o", ms=4, label=f"{joint_names[k]} ({units[k]})")
    ax.set_xticks(range(n), joint_names)
    ax.set_ylabel("joint position (deg; mm for prismatic joints)")
    ax.set_xlabel("joint (poses in measuring order, left to right)")
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.0, 0.5))
    return fig


def poses_3d(flange_mm, markers_mm, marker_names, tracker_mm=None) -> Figure:
    """3-D view of the flange origin (M, 3) and the markers (M, n, 3) at each pose, and the
    tracker (3,) when given; robot base frame, mm."""
    f = np.asarray(flange_mm, float)
    x = np.asarray(markers_mm, float)
    fig = new_figure(7.0, 6.0)
    ax = fig.add_subplot(projection="3d")
    ax.scatter(0, 0, 0, marker="s", s=50, color="k", label="robot base")
    ax.scatter(*f.T, s=25, color="tab:blue", label="flange")
    for i, p in enumerate(f):
        ax.text(*p, str(i + 1), fontsize=7)
    for j, name in enumerate(marker_names):
        ax.scatter(*x[:, j].T, s=8, label=f"marker {name}")
    for p, pts in zip(f, x):
        for pt in pts:
            ax.plot(*np.column_stack([p, pt]), color="0.6", lw=0.6)
    if tracker_mm is not None:
        ax.scatter(*np.asarray(tracker_mm, float), marker="^", s=80, color="tab:red",
                   label="tracker")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_zlabel("z (mm)")
    ax.set_aspect("equal")
    ax.legend(fontsize=7, loc="upper left")
    return fig


def std_bars(names, std, units, title: str = "predicted standard deviation") -> Figure:
    """Standard deviation (P,) of each parameter in display units as bars on a log scale,
    each tick labelled with its name and unit."""
    s = np.asarray(std, float)
    fig = new_figure(min(max(5.0, 0.22 * len(s) + 2.0), 16.0), 3.8)
    ax = fig.add_subplot()
    ax.bar(range(len(s)), np.where(s > 0, s, np.nan), color="tab:green")
    ax.set_yscale("log")
    ax.set_xticks(range(len(s)), [f"{n} [{u}]" for n, u in zip(names, units)], rotation=90,
                  fontsize=max(4.0, min(8.0, 400.0 / max(len(s), 1))))
    ax.set_ylabel("std (unit in brackets)")
    ax.set_title(title)
    return fig


def _box_edges(ax, lower, upper, **style) -> None:
    """The 12 edges of an axis-aligned box."""
    lo, hi = np.asarray(lower, float), np.asarray(upper, float)
    corners = np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]]
                        for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    for a in range(8):
        for b in range(a + 1, 8):
            if bin(a ^ b).count("1") == 1:
                ax.plot(*corners[[a, b]].T, **style)


def robot_poses(skeletons_mm, markers_mm, titles, tracker_mm=None, floor_mm=0.0, boxes=(),
                ncols: int = 4) -> Figure:
    """A grid of small 3-D panels: the robot as a stick figure in each pose, with its cell.

    Every panel has the same equal-scaled axes and view, so that poses compare at a glance.

    ``skeletons_mm`` (M, K, 3): each pose's stick figure, base to flange; ``markers_mm``
    (M, n, 3); ``titles`` (M,); the tracker (3,), the floor's height and keep-out
    ``boxes`` ((lower, upper) each) drawn when given; robot base frame, mm.
    """
    s = np.asarray(skeletons_mm, float)
    x = np.asarray(markers_mm, float)
    pts = [s.reshape(-1, 3), x.reshape(-1, 3)] + [np.asarray(b, float) for box in boxes
                                                  for b in box]
    if tracker_mm is not None:
        pts.append(np.asarray(tracker_mm, float)[None, :])
    pts = np.vstack(pts)
    pts = np.vstack([pts, [pts[0, 0], pts[0, 1], floor_mm]])
    centre = (pts.max(axis=0) + pts.min(axis=0)) / 2
    half = max(float(np.max(pts.max(axis=0) - pts.min(axis=0))) / 2, 1.0) * 1.05
    m = len(s)
    nrows = -(-m // ncols)
    fig = new_figure(2.6 * min(m, ncols), 2.7 * nrows)
    lim = [(c - half, c + half) for c in centre]
    square = np.array([[lim[0][0], lim[1][0]], [lim[0][1], lim[1][0]], [lim[0][1], lim[1][1]],
                       [lim[0][0], lim[1][1]], [lim[0][0], lim[1][0]]])
    for i in range(m):
        ax = fig.add_subplot(nrows, min(m, ncols), i + 1, projection="3d")
        ax.plot(square[:, 0], square[:, 1], floor_mm, color="0.6", lw=0.8)
        ax.plot_trisurf(square[:4, 0], square[:4, 1], np.full(4, floor_mm), color="0.85",
                        alpha=0.4)
        for lower, upper in boxes:
            _box_edges(ax, lower, upper, color="tab:red", lw=0.7)
        ax.plot(*s[i].T, "-o", color="tab:blue", lw=2.0, ms=2.5)
        for p in x[i]:
            ax.plot(*np.column_stack([s[i, -1], p]), color="0.4", lw=0.6)
        ax.scatter(*x[i].T, s=6, color="tab:green")
        if tracker_mm is not None:
            ax.scatter(*np.asarray(tracker_mm, float), marker="^", s=30, color="tab:red")
        ax.set(xlim=lim[0], ylim=lim[1], zlim=lim[2])
        ax.set_box_aspect((1, 1, 1))
        ax.view_init(elev=20, azim=-60)
        if i:  # the same axes in every panel: their numbers once, in the first
            ax.set(xticklabels=[], yticklabels=[], zticklabels=[])
        ax.tick_params(labelsize=7, pad=0)
        ax.set_title(titles[i], fontsize=9)
    fig.subplots_adjust(wspace=0.02, hspace=0.12)
    return fig
