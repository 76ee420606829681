"""The figures' shared style: the DEM's and each model's colours, titles that fit, legends below the axes."""
from __future__ import annotations

import textwrap

from matplotlib.ticker import LogFormatter

#: the DEM is blue (C0); the models take colours no verdict (green, red, grey) nor the DEM has
DEM_COLOUR = "C0"
DRIVE_MARKERS = "o^vD<>"            # the drives' points where several share a panel (all in DEM blues)
MODEL_STYLE = {"local": dict(color="#7b3294", ls="-"), "paper": dict(color="#e08214", ls="--"),
               "ngf": dict(color="#8c510a", ls="-."), "elastic": dict(color="#1b7837", ls=":")}


def wrap(text: str, width_in: float, fontsize: float = 12) -> str:
    """``text`` broken into lines that fit ``width_in`` inches at ``fontsize`` points."""
    return textwrap.fill(" ".join(text.split()), max(20, int(width_in * 72 / (0.6 * fontsize))))


def suptitle(fig, text: str, fontsize: float = 12):
    """A figure title wrapped to the figure's width."""
    fig.suptitle(wrap(text, fig.get_figwidth(), fontsize), fontsize=fontsize)


def plain_log(axis):
    """Plain numbers (2, 3, 10) instead of 2x10^0 on a log axis that spans few decades."""
    axis.set_major_formatter(LogFormatter())
    axis.set_minor_formatter(LogFormatter(labelOnlyBase=False))


def figure_legend(fig, axes, ncols=3, fontsize=8):
    """One legend below the axes for every labelled artist of ``axes`` (each label once)."""
    seen = {}
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            seen.setdefault(lab, h)
    fig.legend(seen.values(), seen.keys(), loc="outside lower center", ncols=ncols, fontsize=fontsize, frameon=False)
