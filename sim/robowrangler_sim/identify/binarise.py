"""Rope pixels of a photo: a local-contrast response, a noise-adaptive threshold with hysteresis, morphology.

A wool rope is thin, fuzzy and (moving along itself at several m/s) smeared along its length; the
background has large objects, gradients and uneven light. What sets the rope apart is that it is thin:

1. response: a grey top-hat (the image minus its morphological opening by a square a few rope widths
   across; a black-hat for a dark rope) keeps structures thinner than the square and removes
   everything wider, whatever its brightness; divided by the local noise level (which uneven light
   and shot noise change across the picture), it is a signal-to-noise ratio, so a faint rope on a
   bright, quiet object counts as much as a bright rope on a dark, noisy one;
2. threshold: the response's own noise level is estimated from the image (median absolute
   deviation: most pixels are background), pixels above ``strong_sigma`` noise levels seed the rope and
   it grows through pixels above ``weak_sigma`` (hysteresis, as in Canny), which keeps faint fuzzy
   parts attached and drops isolated noise;
3. morphology: a small closing bridges one-pixel gaps in the fuzz.
"""

from __future__ import annotations

import cv2
import numpy as np


def local_noise(gray: np.ndarray, *, block_px: int = 32) -> np.ndarray:
    """Image noise level per pixel (float32, H x W): 1.4826 x the median |high-pass| of each block, interpolated.

    The median ignores the few rope pixels of a block, so the rope does not raise its own threshold.
    """
    img = gray.astype(np.float32)
    high = np.abs(img - cv2.GaussianBlur(img, (0, 0), 1.5))[::2, ::2]  # every other pixel is plenty for a median
    h, w = gray.shape
    half = max(block_px // 2, 1)
    bh, bw = max(high.shape[0] // half, 1), max(high.shape[1] // half, 1)
    blocks = high[:bh * half, :bw * half].reshape(bh, half, bw, half).transpose(0, 2, 1, 3)
    sigma = 1.4826 * np.median(blocks.reshape(bh, bw, -1), axis=2).astype(np.float32)
    sigma = cv2.GaussianBlur(sigma, (0, 0), 1.0)
    return np.maximum(cv2.resize(sigma, (w, h), interpolation=cv2.INTER_LINEAR), 0.5)


def rope_response(gray: np.ndarray, *, rope_width_px: float, polarity: str = "bright") -> np.ndarray:
    """Local contrast of thin structures in units of the local noise, float32 (H, W), >= 0.

    Args:
        gray: shape (H, W), uint8.
        rope_width_px: the rope's apparent width (with its fuzz), pixels.
        polarity: "bright" (rope lighter than its background) or "dark".
    """
    if polarity not in ("bright", "dark"):
        raise ValueError(f"polarity: expected 'bright' or 'dark', got {polarity!r}")
    img = cv2.GaussianBlur(gray, (0, 0), 0.8)
    k = int(2 * round(1.5 * max(rope_width_px, 2.0)) + 1)
    kernel = cv2.getStructuringElement(cv2.MORPH_RECT, (k, k))
    op = cv2.MORPH_OPEN if polarity == "bright" else cv2.MORPH_CLOSE
    background = cv2.morphologyEx(img, op, kernel)
    contrast = cv2.absdiff(img, background)  # uint8 morphology: fast
    return contrast.astype(np.float32) / local_noise(gray)


def noise_level(response: np.ndarray) -> float:
    """Robust noise level of the response (1.4826 x median absolute deviation around the median)."""
    sample = response[::3, ::3].ravel()
    med = float(np.median(sample))
    return max(1.4826 * float(np.median(np.abs(sample - med))), 1e-4)


def binarise(response: np.ndarray, *, strong_sigma: float = 7.0, weak_sigma: float = 3.5) -> np.ndarray:
    """Rope mask, uint8 (H, W) in {0, 1}: hysteresis threshold on the response, then a 3 x 3 closing."""
    sigma = noise_level(response)
    med = float(np.median(response[::3, ::3]))
    weak = (response > med + weak_sigma * sigma).astype(np.uint8)
    strong = response > med + strong_sigma * sigma
    n, labels = cv2.connectedComponents(weak, connectivity=8)
    keep = np.zeros(n, bool)
    keep[np.unique(labels[strong])] = True
    keep[0] = False
    mask = keep[labels].astype(np.uint8)
    return cv2.morphologyEx(mask, cv2.MORPH_CLOSE, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3)))
