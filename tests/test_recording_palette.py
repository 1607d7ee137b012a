"""The method palette: ten colours a reader can tell apart, also with a colour-vision
deficiency, readable on the viewer's background, one per compared method.

Colour difference is CIEDE2000 (Sharma, Wu, Dalal 2005; checked against their test
pairs below); deficiencies are simulated in linear RGB with the severity-1 matrices of
Machado, Oliveira, Fernandes (2009).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from scenarios.palette import METHOD_COLOURS, OTHER_COLOURS, method_colour
from scenarios.recording.scene import BACKGROUND

CVD = {  # linear-RGB matrices, severity 1
    "protanopia": [[0.152286, 1.052583, -0.204868], [0.114503, 0.786281, 0.099216],
                   [-0.003882, -0.048116, 1.051998]],
    "deuteranopia": [[0.367322, 0.860646, -0.227968], [0.280085, 0.672501, 0.047413],
                     [-0.011820, 0.042940, 0.968881]],
    "tritanopia": [[1.255528, -0.076749, -0.178779], [-0.078411, 0.930809, 0.147602],
                   [0.004733, 0.691367, 0.303900]],
}
SRGB_TO_XYZ = np.array([[0.4124564, 0.3575761, 0.1804375], [0.2126729, 0.7151522, 0.0721750],
                        [0.0193339, 0.1191920, 0.9503041]])
D65 = np.array([0.95047, 1.0, 1.08883])


def linear(rgb) -> np.ndarray:
    c = np.asarray(rgb, dtype=float) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def srgb(lin: np.ndarray) -> np.ndarray:
    lin = np.clip(lin, 0.0, 1.0)
    return 255.0 * np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * lin ** (1 / 2.4) - 0.055)


def lab(rgb) -> np.ndarray:
    xyz = linear(rgb) @ SRGB_TO_XYZ.T / D65
    d = 6 / 29
    f = np.where(xyz > d**3, np.cbrt(xyz), xyz / (3 * d * d) + 4 / 29)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def ciede2000(lab1: np.ndarray, lab2: np.ndarray) -> float:
    (l1, a1, b1), (l2, a2, b2) = lab1, lab2
    cbar = (np.hypot(a1, b1) + np.hypot(a2, b2)) / 2
    g = 0.5 * (1 - np.sqrt(cbar**7 / (cbar**7 + 25.0**7)))
    a1, a2 = (1 + g) * a1, (1 + g) * a2
    c1, c2 = np.hypot(a1, b1), np.hypot(a2, b2)
    h1, h2 = np.degrees(np.arctan2(b1, a1)) % 360, np.degrees(np.arctan2(b2, a2)) % 360
    dh = 0.0 if c1 * c2 == 0 else (h2 - h1 + 180) % 360 - 180
    d_l, d_c = l2 - l1, c2 - c1
    d_h = 2 * np.sqrt(c1 * c2) * np.sin(np.radians(dh / 2))
    lbar, cbar = (l1 + l2) / 2, (c1 + c2) / 2
    if c1 * c2 == 0:
        hbar = h1 + h2
    elif abs(h1 - h2) <= 180:
        hbar = (h1 + h2) / 2
    else:
        hbar = (h1 + h2 + 360) / 2 if h1 + h2 < 360 else (h1 + h2 - 360) / 2
    t = (1 - 0.17 * np.cos(np.radians(hbar - 30)) + 0.24 * np.cos(np.radians(2 * hbar))
         + 0.32 * np.cos(np.radians(3 * hbar + 6)) - 0.20 * np.cos(np.radians(4 * hbar - 63)))
    s_l = 1 + 0.015 * (lbar - 50) ** 2 / np.sqrt(20 + (lbar - 50) ** 2)
    s_c, s_h = 1 + 0.045 * cbar, 1 + 0.015 * cbar * t
    r_t = (-np.sin(np.radians(60 * np.exp(-(((hbar - 275) / 25) ** 2))))
           * 2 * np.sqrt(cbar**7 / (cbar**7 + 25.0**7)))
    return float(np.sqrt((d_l / s_l) ** 2 + (d_c / s_c) ** 2 + (d_h / s_h) ** 2
                         + r_t * (d_c / s_c) * (d_h / s_h)))


def seen_as(rgb, deficiency: str | None) -> np.ndarray:
    return (np.asarray(rgb, float) if deficiency is None
            else srgb(linear(rgb) @ np.array(CVD[deficiency]).T))


def smallest_difference(colours, deficiency: str | None = None) -> float:
    labs = [lab(seen_as(c, deficiency)) for c in colours]
    return min(ciede2000(a, b) for a, b in itertools.combinations(labs, 2))


@pytest.mark.parametrize(("lab1", "lab2", "expected"), [  # Sharma et al.'s pairs 1, 3, 7
    ((50.0, 2.6772, -79.7751), (50.0, 0.0, -82.7485), 2.0425),
    ((50.0, -1.3802, -84.2814), (50.0, 0.0, -82.7485), 1.0000),
    ((50.0, 0.0, 0.0), (50.0, -1.0, 2.0), 2.3669),
])
def test_ciede2000_matches_the_published_pairs(lab1, lab2, expected):
    assert ciede2000(np.array(lab1), np.array(lab2)) == pytest.approx(expected, abs=1e-4)


def test_every_compared_method_has_its_own_colour():
    from learning.methods.registry import comparison_methods

    assert set(comparison_methods()) <= set(METHOD_COLOURS)
    assert len(set(METHOD_COLOURS.values())) == len(METHOD_COLOURS)


@pytest.mark.parametrize(("deficiency", "least"), [(None, 22.0), ("protanopia", 12.0),
                                                   ("deuteranopia", 11.0),
                                                   ("tritanopia", 16.0)])
def test_the_method_colours_are_far_apart(deficiency, least):
    """tab10 (the earlier palette) scores 16.2, 1.3, 3.3 and 9.5 here."""
    assert smallest_difference(METHOD_COLOURS.values(), deficiency) >= least


def test_colours_read_on_the_viewer_background_and_others_stay_apart():
    bg = lab(BACKGROUND)
    for c in (*METHOD_COLOURS.values(), *OTHER_COLOURS):
        assert ciede2000(lab(c), bg) >= 30, c
    for other in OTHER_COLOURS:
        assert min(ciede2000(lab(other), lab(c)) for c in METHOD_COLOURS.values()) >= 18
    assert method_colour("rnh-ql+ablation") in OTHER_COLOURS
    assert method_colour("haql (grid)") == METHOD_COLOURS["haql"]


def test_a_variants_colour_is_never_a_named_methods():
    """A study's variant (a hashed colour) cannot coincide with a method that has one by
    name, listed or kept: the held-out profiles draw rnh-ql+explore, abstraction-ql and
    rnh-ql+:untried_bonus=1 side by side."""
    from scenarios.palette import METHOD_COLOURS, NAMED_OTHER, method_colour

    named = {method_colour(m) for m in (*METHOD_COLOURS, *NAMED_OTHER)}
    for variant in ("rnh-ql+:untried_bonus=1", "rnh-ql+:untried_bonus=100",
                    "rnh-ql+:untried_bonus=1;n_planning=0", "haql:eps=0.2"):
        assert method_colour(variant) not in named, variant
