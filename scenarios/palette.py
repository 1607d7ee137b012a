"""One colour per method, shared by the PNG figures and the Rerun recordings.

A method keeps its colour in every figure, recording and process (no order-
dependent cycling, no salted hash), so a reader can match a curve in a PNG to
the same method in the viewer.
"""

from __future__ import annotations

import zlib

METHOD_COLOURS: dict[str, tuple[int, int, int]] = {  # RGB, tab10's hues
    "rnh-ql": (214, 39, 40),  # red
    "rnh-ql+": (31, 119, 180),  # blue
    "haql": (44, 160, 44),  # green
    "dyna-q": (148, 103, 189),  # purple
    "q-lambda": (255, 127, 14),  # orange
    "st-ql": (127, 127, 127),  # grey
    "rn-ql": (140, 86, 75),  # brown
    "pfh-rl": (188, 189, 34),  # olive
    "sarsa-rs": (227, 119, 194),  # pink
    "q-opt": (23, 190, 207),  # cyan
}
OTHER_COLOURS = ((60, 60, 60), (0, 120, 120), (160, 100, 0), (100, 60, 160))


def method_colour(method: str) -> tuple[int, int, int]:
    """The method's RGB colour; a method not listed gets one by a stable hash of its name."""
    base = method.split(" ", 1)[0]  # "rnh-ql+ (issue ...)" or "haql (grid)" -> the method
    if base in METHOD_COLOURS:
        return METHOD_COLOURS[base]
    return OTHER_COLOURS[zlib.crc32(method.encode()) % len(OTHER_COLOURS)]


def method_colour_mpl(method: str) -> tuple[float, float, float]:
    """:func:`method_colour` for matplotlib (0..1)."""
    r, g, b = method_colour(method)
    return (r / 255.0, g / 255.0, b / 255.0)
