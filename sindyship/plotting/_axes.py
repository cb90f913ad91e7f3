"""The one axes helper every plot uses: new figures without pyplot state, or the caller's axes."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

__all__ = ["figure_axes", "single_axes"]


def figure_axes(ax, shape: tuple[int, int], figsize: tuple[float, float], **subplots
                ) -> tuple[Figure, list]:
    """The figure and a flat list of axes: new ones of ``shape``, or those given in ``ax``.

    Figures are :class:`matplotlib.figure.Figure` objects made directly (no pyplot state), so
    a caller never has to close them.

    Parameters
    ----------
    ax : matplotlib Axes, sequence of Axes, or None
        Where to draw; None makes a new figure.
    shape : (int, int)
        Rows and columns of a new figure's axes grid (and the number of axes ``ax`` must hold).
    figsize : (float, float)
        Size of a new figure [inch].
    **subplots
        Passed to :meth:`matplotlib.figure.Figure.subplots` (``sharex``, ``height_ratios``).

    Returns
    -------
    (Figure, list of Axes)

    Examples
    --------
    >>> fig, (top, bottom) = figure_axes(None, (2, 1), (4.0, 3.0), sharex=True)
    >>> len(fig.axes)
    2
    """
    n = shape[0] * shape[1]
    if ax is None:
        fig = Figure(figsize=figsize, layout="constrained")
        axes = fig.subplots(*shape, squeeze=False, **subplots).ravel().tolist()
        return fig, axes
    axes = list(np.ravel(np.asarray(ax, dtype=object))) if not hasattr(ax, "plot") else [ax]
    if len(axes) != n:
        raise ValueError(f"this figure needs {n} axes, not {len(axes)}")
    return axes[0].figure, axes


def single_axes(ax, figsize: tuple[float, float]):
    """The figure and one axes: a new figure of ``figsize``, or the caller's ``ax``."""
    fig, (axis,) = figure_axes(ax, (1, 1), figsize)
    return fig, axis
