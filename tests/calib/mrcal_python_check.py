#!/usr/bin/env python3
"""Cross-check of glasspiv's mrcal .cameramodel files against mrcal itself.

Run by camera_file_test (tests/calib/camera_file_test.cpp) when python3-mrcal is
installed:

    mrcal_python_check.py OURS.cameramodel MRCAL_WRITTEN.cameramodel POINTS.txt \
                          OUT_OURS.txt OUT_MRCAL.txt

1. Loads OURS.cameramodel (written by glasspiv) with mrcal and projects the
   world points of POINTS.txt (one "x y z" per line, mm) through its extrinsics
   and intrinsics into OUT_OURS.txt ("u v" per line).
2. Builds a camera with mrcal (LENSMODEL_OPENCV8 and a pose), writes it with
   mrcal.cameramodel.write to MRCAL_WRITTEN.cameramodel, loads that file again
   and projects the same points into OUT_MRCAL.txt, for glasspiv to read the
   file mrcal wrote and compare.
"""
import sys

import numpy as np
import mrcal


def project(model, points_ref):
    points_cam = mrcal.transform_point_rt(model.extrinsics_rt_fromref(), points_ref)
    lensmodel, intrinsics = model.intrinsics()
    return mrcal.project(points_cam, lensmodel, intrinsics)


def save(path, q):
    with open(path, "w") as f:
        for u, v in q:
            f.write(f"{u!r} {v!r}\n")


def main():
    ours_path, mrcal_path, points_path, out_ours, out_mrcal = sys.argv[1:6]
    points = np.loadtxt(points_path, ndmin=2)

    ours = mrcal.cameramodel(ours_path)
    save(out_ours, project(ours, points))

    made = mrcal.cameramodel(
        intrinsics=("LENSMODEL_OPENCV8",
                    np.array([1450.25, 1449.75, 1015.5, 771.25,
                              -0.21, 0.085, 3e-4, -2e-4, -0.012, 0.004, -0.002, 0.001])),
        imagersize=(2048, 1536),
        extrinsics_rt_fromref=np.array([0.05, -0.3, 0.02, 12.5, -4.0, 640.0]))
    made.write(mrcal_path)
    save(out_mrcal, project(mrcal.cameramodel(mrcal_path), points))


if __name__ == "__main__":
    main()
