#!/usr/bin/env python3
"""Per-frame rotation bias of stereo visual odometry on a KITTI folder, against two independent
OpenCV references, to tell a bias of the data (calibration, ground truth) from one of svslam.

  python3 scripts/reference_vo_kitti.py KITTI_DIR [svslam trajectory_kitti.txt ...]
  python3 scripts/reference_vo_kitti.py --regions KITTI_DIR

--regions: the KLT reference on subsets of its points instead (left / right of the principal
point, above / below it, nearer / farther than 15 m): which part of the scene carries a bias.

For every frame k the relative rotation R_{k-1,k} (camera k in camera k-1) of each method is
compared with the ground truth's: e_k = log(R_gt R_est^T), in the camera frame (x right, y down,
z forward: e_z is the roll about the optical axis). Printed in millidegrees per frame: the mean
(a bias: it grows linearly along the path) and the RMS, over all frames and from frame 12 on
(the ground truth of kitti_odometry_seq_a is interpolated over frames 1-12, docs/slam.md).
References, both with RANSAC PnP (1 px) on the previous frame's stereo points, refined by LM:
  orb: cv2.ORB (4000 points) on both images, brute-force Hamming matching (stereo: same row
       within 1 px, disparity >= 2 px; temporal: cross-checked);
  klt: Shi-Tomasi corners, pyramidal KLT left->right (same row within 1 px) and to the next frame.
Needs the Debian packages python3-numpy and python3-opencv.
"""
import glob
import sys

import cv2
import numpy as np


def load_kitti_poses(path):
    out = []
    for line in open(path):
        if line.strip():
            m = np.eye(4)
            m[:3, :4] = np.array([float(x) for x in line.split()]).reshape(3, 4)
            out.append(m)
    return out


def log_so3(r):
    c = np.clip((np.trace(r) - 1) / 2, -1, 1)
    th = np.arccos(c)
    w = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    return w * (th / (2 * np.sin(th)) if th > 1e-9 else 0.5)


def main():
    args = sys.argv[1:]
    regions = bool(args) and args[0] == "--regions"
    if regions:
        args = args[1:]
    d = args[0]
    proj = [np.array([float(x) for x in l.split()[-12:]]).reshape(3, 4)
            for l in open(d + "/calib.txt") if l.strip()][:2]
    f, cx, cy = proj[0][0, 0], proj[0][0, 2], proj[0][1, 2]
    b = -proj[1][0, 3] / proj[1][0, 0]
    K = np.array([[f, 0, cx], [0, f, cy], [0, 0, 1.0]])
    left = sorted(glob.glob(d + "/image_l/*.png") + glob.glob(d + "/image_0/*.png"))
    right = sorted(glob.glob(d + "/image_r/*.png") + glob.glob(d + "/image_1/*.png"))
    gt = load_kitti_poses(d + "/poses.txt")

    def error(r_rel_est, k):  # e_k in rad, camera frame
        g = np.linalg.inv(gt[k - 1]) @ gt[k]
        return log_so3(g[:3, :3] @ r_rel_est.T)

    def xyz(p, disp):
        z = f * b / disp
        return np.stack([(p[:, 0] - cx) * z / f, (p[:, 1] - cy) * z / f, z], 1).astype(np.float32)

    def pnp(obj, img):  # camera k-1 -> k motion; returns R_{k-1,k}
        _, rv, tv, inl = cv2.solvePnPRansac(obj, img, K, None, iterationsCount=500,
                                            reprojectionError=1.0)
        i = inl[:, 0]
        rv, tv = cv2.solvePnPRefineLM(obj[i], img[i], K, None, rv, tv)
        return cv2.Rodrigues(rv)[0].T

    orb = cv2.ORB_create(4000, fastThreshold=10)
    bf = cv2.BFMatcher(cv2.NORM_HAMMING, crossCheck=True)

    def orb_frame(k):
        a, c = cv2.imread(left[k], 0), cv2.imread(right[k], 0)
        ka, da = orb.detectAndCompute(a, None)
        kc, dc = orb.detectAndCompute(c, None)
        keep = [m for m in bf.match(da, dc)
                if abs(ka[m.queryIdx].pt[1] - kc[m.trainIdx].pt[1]) <= 1
                and ka[m.queryIdx].pt[0] - kc[m.trainIdx].pt[0] >= 2]
        p = np.array([ka[m.queryIdx].pt for m in keep], np.float32)
        disp = p[:, 0] - np.array([kc[m.trainIdx].pt[0] for m in keep], np.float32)
        return xyz(p, disp), np.array([da[m.queryIdx] for m in keep]), p

    subsets = {
        "klt, left half": lambda p, z: p[:, 0] < cx, "klt, right half": lambda p, z: p[:, 0] >= cx,
        "klt, above cy": lambda p, z: p[:, 1] < cy, "klt, below cy": lambda p, z: p[:, 1] >= cy,
        "klt, nearer than 15 m": lambda p, z: z < 15, "klt, 15 m or farther": lambda p, z: z >= 15,
    } if regions else {}
    results = {"orb": [], "klt": []}
    results.update({name: [] for name in subsets})
    prev = orb_frame(0)
    for k in range(1, len(left)):
        cur = orb_frame(k)
        m = bf.match(prev[1], cur[1])
        obj = np.array([prev[0][x.queryIdx] for x in m])
        img = np.array([cur[2][x.trainIdx] for x in m])
        results["orb"].append(error(pnp(obj, img), k))
        prev = cur

        a, c, n = cv2.imread(left[k - 1], 0), cv2.imread(right[k - 1], 0), cv2.imread(left[k], 0)
        pts = cv2.goodFeaturesToTrack(a, 3000, 0.005, 8)
        pr, s1, _ = cv2.calcOpticalFlowPyrLK(a, c, pts, None, winSize=(11, 11), maxLevel=3)
        pn, s2, _ = cv2.calcOpticalFlowPyrLK(a, n, pts, None, winSize=(11, 11), maxLevel=3)
        p, q, t = pts[:, 0], pr[:, 0], pn[:, 0]
        disp = p[:, 0] - q[:, 0]
        ok = (s1[:, 0] == 1) & (s2[:, 0] == 1) & (np.abs(p[:, 1] - q[:, 1]) < 1) & (disp > 2)
        obj, img = xyz(p[ok], disp[ok]), t[ok].astype(np.float32)
        results["klt"].append(error(pnp(obj, img), k))
        for name, inside in subsets.items():
            m = inside(p[ok], obj[:, 2])
            results[name].append(error(pnp(obj[m], img[m]), k))

    for path in args[1:]:
        est = load_kitti_poses(path)
        results[path] = [error((np.linalg.inv(est[k - 1]) @ est[k])[:3, :3], k)
                         for k in range(1, len(est))]

    print("per-frame rotation error, mdeg, camera axes (x, y, z = roll about the optical axis)")
    for name, e in results.items():
        e = np.degrees(np.array(e)) * 1e3
        print("%-40s mean %s  rms %s  | from frame 12: mean %s" % (
            name, np.round(e.mean(0), 1), np.round(np.sqrt((e ** 2).mean(0)), 1),
            np.round(e[11:].mean(0), 1)))


if __name__ == "__main__":
    main()
