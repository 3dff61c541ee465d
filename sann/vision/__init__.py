"""Vision for the multi-cup task: the cup, the camera, piles in a box, rendering, labels, poses.

Modules: ``cup`` (the revolved mesh), ``camera`` (intrinsics, poses, projections), ``piles``
(the box and MuJoCo drops), ``render`` (embree depth/colour/instance images), ``labels``
(visible fractions, graspability, which cup lies on which), ``detect`` (LineMod and
Patch-LineMod pose estimation).

``sann.vision.detect_cups(rgb, depth_mm, K)`` is the entry point for any RGB-D frame; it is
imported on first use, so importing the package stays cheap (no OpenCV, no templates).
"""

from __future__ import annotations

from typing import Any

__all__ = ["detect_cups"]


def __getattr__(name: str) -> Any:
    if name == "detect_cups":
        from sann.vision.detect import detect_cups

        return detect_cups
    raise AttributeError(f"module 'sann.vision' has no attribute {name!r}")
