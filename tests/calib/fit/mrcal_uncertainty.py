#!/usr/bin/env python3
"""mrcal's fit of a corners.vnl and its projection uncertainty, for the
glasspiv uncertainty tests (tests/calib/fit/projection_uncertainty_test.cpp
writes the corners.vnl with glasspiv's own writer and reads OUT.txt).

    mrcal_uncertainty.py CORNERS.vnl OBJECT_W OBJECT_H SPACING WIDTH HEIGHT
                         LENSMODEL FOCAL_ESTIMATE SEED DISTANCE OUT.txt U V [U V ...]

mrcal reads the corners back (mrcal.compute_chessboard_corners, the reader
mrcal-calibrate-cameras uses) and fits them as tests/calib/fit/mrcal_fit.py
does: seed_stereographic, the core with no distortion, everything regularised,
then everything without regularisation, outlier rejection or board warp: the
same least-squares cost as glasspiv's. SEED "-" starts so; otherwise it is
the comma-separated intrinsics to start from (another local optimum of a rich
model): the board poses are fitted with them held, then everything. The model keeps its
optimization_inputs (regularisation off, as in the final pass), and
mrcal.projection_uncertainty gives the worst-direction 1-sigma of each query
pixel, its ray taken to DISTANCE and to infinity, the noise estimated from
the residuals (mrcal's default).

OUT.txt: line 1 the fitted intrinsics, line 2 the RMS over the corners
(sqrt(mean |r|^2)), line 3 the noise estimate mrcal uses (np.std of the
residuals), then one line per query pixel: "sigma_at_distance sigma_at_infinity".
"""
import sys

import numpy as np
import mrcal


def main():
    (vnl, object_w, object_h, spacing, width, height, lensmodel, focal, seed, distance,
     out_path) = sys.argv[1:12]
    object_w, object_h, width, height = int(object_w), int(object_h), int(width), int(height)
    spacing, focal, distance = float(spacing), float(focal), float(distance)
    q = np.array([float(x) for x in sys.argv[12:]]).reshape(-1, 2)

    observations, indices_frame_camera, _ = mrcal.compute_chessboard_corners(
        object_w, object_h, corners_cache_vnl=vnl, weight_column_kind='level')
    nviews = len(observations)
    imagersizes = np.array([[width, height]], dtype=np.int32)

    # mrcal 2.2's seeding (its solvePnP call) drops NaN corners but not the
    # weight < 0 ones: hand it NaN for unseen corners.
    seed_observations = observations.copy()
    seed_observations[seed_observations[..., 2] < 0] = np.nan
    core, _, frames = mrcal.seed_stereographic(
        imagersizes=imagersizes, focal_estimate=focal, indices_frame_camera=indices_frame_camera,
        observations=seed_observations, object_spacing=spacing)
    ndistortion = mrcal.lensmodel_num_params(lensmodel) - 4
    intrinsics = np.hstack((core[:, :4], np.zeros((1, ndistortion))))
    extrinsics = np.zeros((0, 6))
    indices = np.array([(i, 0, -1) for i in range(nviews)], dtype=np.int32)

    def inputs(distortions, regularization):
        return dict(intrinsics=intrinsics, extrinsics_rt_fromref=extrinsics, frames_rt_toref=frames,
                    points=None, observations_board=observations,
                    indices_frame_camintrinsics_camextrinsics=indices,
                    observations_point=None, indices_point_camintrinsics_camextrinsics=None,
                    lensmodel=lensmodel, imagersizes=imagersizes, calibration_object_spacing=spacing,
                    do_optimize_intrinsics_core=True, do_optimize_intrinsics_distortions=distortions,
                    do_optimize_extrinsics=True, do_optimize_frames=True,
                    do_optimize_calobject_warp=False, calobject_warp=None,
                    do_apply_outlier_rejection=False, do_apply_regularization=regularization)

    if seed != "-":
        intrinsics[0] = [float(x) for x in seed.split(",")]
        frames_only = inputs(False, False)
        frames_only["do_optimize_intrinsics_core"] = False
        mrcal.optimize(**frames_only, verbose=False)
        final = inputs(True, False)
        mrcal.optimize(**final, verbose=False)
    elif ndistortion > 0:
        mrcal.optimize(**inputs(False, False), verbose=False)
        mrcal.optimize(**inputs(True, True), verbose=False)
        final = inputs(True, False)
        mrcal.optimize(**final, verbose=False)
    else:
        final = inputs(False, False)
        mrcal.optimize(**final, verbose=False)

    board = mrcal.ref_calibration_object(object_w, object_h, spacing)
    projected = mrcal.project(mrcal.transform_point_rt(frames[:, None, None, :], board), lensmodel, intrinsics[0])
    seen = observations[..., 2] > 0
    residuals = projected[seen] - observations[..., :2][seen]
    rms = np.sqrt(np.mean(np.sum(residuals * residuals, axis=-1)))

    model = mrcal.cameramodel(optimization_inputs=final, icam_intrinsics=0)
    _, x, _, _ = mrcal.optimizer_callback(**final)
    noise = np.std(mrcal.residuals_chessboard(final, residuals=x).ravel())
    v = mrcal.unproject(q, lensmodel, intrinsics[0], normalize=True)
    at_distance = mrcal.projection_uncertainty(v * distance, model, what='worstdirection-stdev')
    at_infinity = mrcal.projection_uncertainty(v, model, atinfinity=True, what='worstdirection-stdev')

    with open(out_path, "w") as f:
        f.write(" ".join(repr(float(x)) for x in intrinsics[0]) + "\n")
        f.write(repr(float(rms)) + "\n")
        f.write(repr(float(noise)) + "\n")
        for a, b in zip(np.atleast_1d(at_distance), np.atleast_1d(at_infinity)):
            f.write(f"{float(a)!r} {float(b)!r}\n")


if __name__ == "__main__":
    main()
