"""Colour segmentation: hue/saturation/value masks and the largest connected region of a mask."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from behaviors.perception.errors import InvalidImage


@dataclass(frozen=True, slots=True)
class ColourRange:
    """Pixels whose hue is within `hue_tolerance_deg` of `hue_deg` and saturation and value are high enough."""

    hue_deg: float
    hue_tolerance_deg: float = 20.0
    min_saturation: float = 0.5  # (max - min) / max of r, g, b
    min_value: float = 0.15  # max of r, g, b over 255


#: The can is red, the trash box lid green (robot/hrp2/README.md, EXPO scene colours).
RED = ColourRange(hue_deg=0.0)
GREEN = ColourRange(hue_deg=130.0, hue_tolerance_deg=25.0)
#: The unknown trash of [OP] Fig. 8 (robot/scene_trash.py) is orange: hue 28 deg, between the can's red and yellow.
ORANGE = ColourRange(hue_deg=28.0, hue_tolerance_deg=10.0, min_saturation=0.6)


def hsv(rgb) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hue [deg, 0..360), saturation [0..1] and value [0..1] of an (H, W, 3) uint8 image."""
    a = np.asarray(rgb)
    if a.ndim != 3 or a.shape[2] != 3 or a.dtype != np.uint8:
        raise InvalidImage(f"rgb must be an (H, W, 3) uint8 image, got shape {a.shape} dtype {a.dtype}")
    r, g, b = (a[..., k].astype(np.float32) * np.float32(1 / 255) for k in range(3))
    maxc = np.maximum(np.maximum(r, g), b)  # channel-wise: ~10x faster than a reduction over the last axis
    minc = np.minimum(np.minimum(r, g), b)
    chroma = maxc - minc
    safe = np.where(chroma > 0, chroma, 1.0)
    hue = np.where(maxc == r, np.mod((g - b) / safe, 6.0),
                   np.where(maxc == g, (b - r) / safe + 2.0, (r - g) / safe + 4.0)) * 60.0
    hue = np.where(chroma > 0, hue, 0.0)
    saturation = np.where(maxc > 0, chroma / np.where(maxc > 0, maxc, 1.0), 0.0)
    return hue, saturation, maxc


def colour_mask(rgb, colour: ColourRange) -> np.ndarray:
    """(H, W) bool: the pixels of that colour (hue computed only where saturation and value pass)."""
    a = np.asarray(rgb)
    if a.ndim != 3 or a.shape[2] != 3 or a.dtype != np.uint8:
        raise InvalidImage(f"rgb must be an (H, W, 3) uint8 image, got shape {a.shape} dtype {a.dtype}")
    maxc = np.maximum(np.maximum(a[..., 0], a[..., 1]), a[..., 2])
    minc = np.minimum(np.minimum(a[..., 0], a[..., 1]), a[..., 2])
    chroma = maxc.astype(np.int16) - minc
    candidate = (maxc >= colour.min_value * 255) & (chroma >= colour.min_saturation * maxc.astype(np.float32))
    candidate &= chroma > 0
    mask = np.zeros(a.shape[:2], dtype=bool)
    if candidate.any():
        hue, _, _ = hsv(a[candidate][None])
        dh = np.abs(np.mod(hue[0] - colour.hue_deg + 180.0, 360.0) - 180.0)
        mask[candidate] = dh <= colour.hue_tolerance_deg
    return mask


def largest_region(mask) -> np.ndarray:
    """(H, W) bool: the largest 8-connected region of `mask` (all False if the mask is empty)."""
    labels, n = ndimage.label(np.asarray(mask, dtype=bool), structure=np.ones((3, 3), dtype=bool))
    if n == 0:
        return np.zeros_like(mask, dtype=bool)
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    return labels == int(np.argmax(sizes))
