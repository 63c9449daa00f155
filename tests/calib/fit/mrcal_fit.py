#!/usr/bin/env python3
"""mrcal's fit of the same board observations, for the glasspiv fit tests and
fit_bench (tests/calib/fit/mrcal_peer.cpp writes the input and reads the output).

    mrcal_fit.py IN.json OUT.txt

IN.json: {"width", "height", "lensmodel" (e.g. "LENSMODEL_OPENCV5"),
          "board_cols", "board_rows", "spacing_mm", "focal_estimate_px",
          "views": [[[col, row, u, v], ...], ...]}
OUT.txt: line 1 the fitted intrinsics (fx fy cx cy distortion...), line 2 the
RMS reprojection error over the corners (sqrt(mean |r|^2), OpenCV's
definition), line 3 the seconds spent in mrcal.optimize (all passes).

The fit follows mrcal-calibrate-cameras' recipe with the extras switched off so
that it minimises the same cost as glasspiv and OpenCV: seed with
mrcal.seed_stereographic, optimise the core (fx fy cx cy) and the board poses
with the distortion at zero, then everything (regularised, then not). The
final pass has no regularisation, no outlier rejection and a flat board (no
calobject_warp).
"""
import json
import sys
import time

import numpy as np
import mrcal


def main():
    in_path, out_path = sys.argv[1:3]
    with open(in_path) as f:
        d = json.load(f)
    cols, rows, spacing = d["board_cols"], d["board_rows"], d["spacing_mm"]
    lensmodel = d["lensmodel"]
    nviews = len(d["views"])

    observations = np.zeros((nviews, rows, cols, 3))
    observations[..., 2] = -1.0  # corners not seen count as outliers
    for i, view in enumerate(d["views"]):
        for col, row, u, v in view:
            observations[i, int(row), int(col)] = (u, v, 1.0)
    imagersizes = np.array([[d["width"], d["height"]]], dtype=np.int32)
    indices_frame_camera = np.array([(i, 0) for i in range(nviews)], dtype=np.int32)

    # mrcal 2.2's seeding (its solvePnP call) drops NaN corners but not the
    # weight < 0 ones its documentation mentions: hand it NaN for unseen corners.
    seed_observations = observations.copy()
    seed_observations[seed_observations[..., 2] < 0] = np.nan
    core, extrinsics, frames = mrcal.seed_stereographic(
        imagersizes=imagersizes, focal_estimate=d["focal_estimate_px"],
        indices_frame_camera=indices_frame_camera, observations=seed_observations,
        object_spacing=spacing)
    ndistortion = mrcal.lensmodel_num_params(lensmodel) - 4
    intrinsics = np.hstack((core[:, :4], np.zeros((1, ndistortion))))
    extrinsics = np.zeros((0, 6))
    indices = np.array([(i, 0, -1) for i in range(nviews)], dtype=np.int32)

    def optimize(distortions, regularization):
        return mrcal.optimize(intrinsics, extrinsics, frames, None, observations, indices, None, None,
                              lensmodel, imagersizes=imagersizes,
                              calibration_object_spacing=spacing,
                              do_optimize_intrinsics_core=True,
                              do_optimize_intrinsics_distortions=distortions,
                              do_optimize_extrinsics=False, do_optimize_frames=True,
                              do_optimize_calobject_warp=False, calobject_warp=None,
                              do_apply_outlier_rejection=False,
                              do_apply_regularization=regularization,
                              verbose=False)

    start = time.perf_counter()
    optimize(False, False)
    if ndistortion > 0:
        # Straight from zero distortion, the unregularised rational models
        # (opencv8) stall in a poor minimum (RMS 0.46 px instead of 0.137 px);
        # a regularised pass first, as mrcal itself always regularises, then
        # the plain least-squares pass that matches glasspiv's and OpenCV's cost.
        optimize(True, True)
        optimize(True, False)
    seconds = time.perf_counter() - start

    board = mrcal.ref_calibration_object(cols, rows, spacing)
    q = mrcal.project(mrcal.transform_point_rt(frames[:, None, None, :], board), lensmodel, intrinsics[0])
    seen = observations[..., 2] > 0
    residuals = q[seen] - observations[..., :2][seen]
    rms = np.sqrt(np.mean(np.sum(residuals * residuals, axis=-1)))

    with open(out_path, "w") as f:
        f.write(" ".join(repr(float(x)) for x in intrinsics[0]) + "\n")
        f.write(repr(float(rms)) + "\n")
        f.write(repr(seconds) + "\n")


if __name__ == "__main__":
    main()
