"""Terrain height h(x, y) from a DIR/terrains/<scene>.json spec (same
conventions as core/terrains.h)."""

import math

import numpy as np


def _gaussians(spec, x, y):
    h = np.zeros_like(x, dtype=float)
    for bump in spec.get("bumps", []):
        amplitude, bx, by, sigma = (float(v) for v in bump[:4])
        h += amplitude * np.exp(-((x - bx) ** 2 + (y - by) ** 2) / (2 * sigma ** 2))
    return h


def _plane(spec, x, y):
    return np.full_like(x, float(spec.get("height", 0.0)), dtype=float)


def _incline(spec, x, y):
    beta = math.radians(float(spec.get("slope_deg", 0.0)))
    gamma = math.radians(float(spec.get("azimuth_deg", 0.0)))
    return float(spec.get("height", 0.0)) + math.tan(beta) * (
        math.cos(gamma) * x + math.sin(gamma) * y)


_HEIGHTS = {"gaussians": _gaussians, "plane": _plane, "incline": _incline}


def terrain_height(spec, x, y):
    """Height grid for arrays x, y (same shape)."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    return _HEIGHTS[spec["type"]](spec, x, y)


def describe_terrain(spec):
    if spec is None:
        return "no terrain description"
    kind = spec["type"]
    if kind == "gaussians":
        return f"{len(spec.get('bumps', []))} Gaussian bumps"
    if kind == "plane":
        return f"plane at h = {float(spec.get('height', 0.0)):g} m"
    return (f"incline of {float(spec.get('slope_deg', 0.0)):g}° towards azimuth "
            f"{float(spec.get('azimuth_deg', 0.0)):g}°")
