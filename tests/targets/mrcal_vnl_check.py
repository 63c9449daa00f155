#!/usr/bin/env python3
"""Reads a corners.vnl with mrcal's own reader and prints what it got.

usage: mrcal_vnl_check.py CORNERS.vnl WIDTH HEIGHT
prints one line per view mrcal kept: "<file> <valid points> <x of point 0> <y of point 0>"
exit 3 when mrcal cannot be imported (the caller skips).
"""
import sys

try:
    import mrcal
except ImportError:
    sys.exit(3)

path, width, height = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
observations, indices, paths = mrcal.compute_chessboard_corners(
    width, height, globs_per_camera=("*",), corners_cache_vnl=path, jobs=-1)
for obs, p in zip(observations, paths):
    valid = obs[..., 2] > 0
    print(f"{p} {int(valid.sum())} {obs[0, 0, 0]!r} {obs[0, 0, 1]!r}")
