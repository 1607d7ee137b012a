"""The scaling study's figure: episodes to a stable optimal route and wall time per run
against states, log-log, one line per method in its palette colour (drawn from the study's
rows, or from its artifact by ``rnhql report --figures``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from scenarios.figures.mpl import pyplot
from scenarios.figures.save import save_figure
from scenarios.palette import method_colour_mpl


def figure(rows: dict[str, list[dict[str, Any]]], path: Path, title: str) -> None:
    # lazy: matplotlib costs 270 ms at import; the docs' Cog blocks import this module
    # (through scaling_maps_figure) and never draw
    plt = pyplot()

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), dpi=110)
    for method, pts in rows.items():
        colour = method_colour_mpl(method)
        for ax, key in zip(axes, ("episodes", "wall"), strict=True):
            xs = [p["states"] for p in pts if p[key]["median"] is not None]
            med = [p[key]["median"] for p in pts if p[key]["median"] is not None]
            lo = [p[key]["q25"] or p[key]["median"] for p in pts if p[key]["median"] is not None]
            hi = [p[key]["q75"] or p[key]["median"] for p in pts if p[key]["median"] is not None]
            if xs:
                ax.errorbar(xs, med, yerr=[np.subtract(med, lo), np.subtract(hi, med)],
                            marker="o", color=colour, capsize=3,
                            label=f"{method} (exponent {pts[0]['fit'][key]})")
    for ax, label in zip(axes, ("episodes to a stable optimal route", "wall time per run [s]"),
                         strict=True):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("states (cells)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)
