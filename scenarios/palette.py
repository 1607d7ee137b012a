"""One colour per method, shared by the PNG figures and the Rerun recordings.

A method keeps its colour in every figure, recording and process (no order-
dependent cycling, no salted hash), so a reader can match a curve in a PNG to
the same method in the viewer.

Ten curves in one panel need ten colours a reader can tell apart, also with the
commonest colour-vision deficiencies. matplotlib's tab10 (the earlier palette) has
pairs that nearly coincide for protanopes (haql green / q-lambda orange:
CIEDE2000 1.3) and deuteranopes (q-lambda / pfh-rl: 3.3). These ten were chosen by a
farthest-point search over sRGB (steps of 12) for the largest smallest CIEDE2000
difference, counted in normal vision and in simulated protanopia, deuteranopia
(weighted x2) and tritanopia (x1.3; Machado et al. 2009, severity 1), among colours
dark enough to read on the viewer's light background; each method then took the
one nearest its old hue. The reference methods added later (LRTA*, the free-space
replanner, then R-max) took the colours of the same search that stay farthest from those
before them and from the other colours. Smallest differences: at least 22 normal, 12
protan, 11 deutan, 16 tritan (tests/test_recording_palette.py checks the bounds).
"""

from __future__ import annotations

import zlib

METHOD_COLOURS: dict[str, tuple[int, int, int]] = {  # RGB
    "rnh-ql": (156, 0, 12),  # dark red
    "rnh-ql+": (0, 48, 252),  # blue
    "haql": (0, 120, 84),  # green
    "dyna-q": (132, 12, 108),  # plum
    "q-lambda": (144, 108, 0),  # ochre
    "st-ql": (72, 72, 72),  # dark grey
    "rn-ql": (240, 108, 132),  # pink
    "pfh-rl": (132, 168, 24),  # lime
    "sarsa-rs": (132, 120, 156),  # lilac grey
    "q-opt": (72, 156, 252),  # sky blue
    "lrta-star": (0, 0, 48),  # navy
    "fsa-replan": (0, 252, 120),  # spring green
    "r-max": (48, 0, 0),  # maroon
}
# methods without a colour of their own (a study's variant): the next four of the same
# search, each far from the method colours (CIEDE2000 >= 18)
OTHER_COLOURS = ((252, 108, 12), (252, 0, 252), (12, 156, 168), (144, 108, 96))
# two methods that kept the colour their name's hash gave them, so a variant's hash
# (rnh-ql+:untried_bonus=1 beside them in the held-out profiles) cannot land on it
NAMED_OTHER = {"rnh-ql+explore": OTHER_COLOURS[1], "abstraction-ql": OTHER_COLOURS[3]}
VARIANT_COLOURS = tuple(c for c in OTHER_COLOURS if c not in NAMED_OTHER.values())


def method_colour(method: str) -> tuple[int, int, int]:
    """The method's RGB colour; a method not listed gets one by a stable hash of its name."""
    base = method.split(" ", 1)[0]  # "rnh-ql+ (a variant)" or "haql (grid)" -> the method
    if base in METHOD_COLOURS:
        return METHOD_COLOURS[base]
    if base in NAMED_OTHER:
        return NAMED_OTHER[base]
    return VARIANT_COLOURS[zlib.crc32(method.encode()) % len(VARIANT_COLOURS)]


def method_colour_mpl(method: str) -> tuple[float, float, float]:
    """:func:`method_colour` for matplotlib (0..1)."""
    r, g, b = method_colour(method)
    return (r / 255.0, g / 255.0, b / 255.0)
