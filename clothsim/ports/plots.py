"""Figures of the port commands: the deviation of a trajectory from its reference."""

from __future__ import annotations

import numpy as np

from ..io.common import atomic_path


def plot_deviation(comparison, path) -> None:
    """Write the max and RMS error per frame, with the tolerance, as an image (log scale).

    Parameters
    ----------
    comparison : clothsim.ports.compare.Comparison
    path : path
        Image file (``.png``, ``.svg``, … by matplotlib).

    Returns
    -------
    None
        The figure is written to ``path``.
    """
    from matplotlib.figure import Figure  # no pyplot: the user's backend is left alone

    f = np.arange(comparison.frames)
    fig = Figure(figsize=(6, 3.5))
    ax = fig.add_subplot()

    def positive(e):  # exact zeros (frame 0) are left out of the log scale
        return np.where(e > 0, e, np.nan)

    ax.semilogy(f, positive(comparison.max_error), ".-", label="max error")
    ax.semilogy(f, positive(comparison.rms_error), ".-", label="RMS error")
    ax.semilogy(f, comparison.tolerance, "k--", label="tolerance")
    if comparison.first_frame is not None:
        ax.axvline(comparison.first_frame, color="r", lw=0.8, label="first failure")
    ax.set_xlabel("frame")
    ax.set_ylabel(f"{comparison.field} error [m]")
    ax.legend(fontsize=8)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100)
