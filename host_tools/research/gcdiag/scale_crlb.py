#!/usr/bin/env python3
"""scale_crlb.py - how well can any estimator know gc's metric scale? The Cramer-Rao bound of
the scale of the paper's four single cameras (cam1 front, cam2 right, cam3 back, cam4 left, each
0.1 m from cam1) under the paper's motion, with every landmark free (no depth prior) and the
pose of the first frame held.

The rig's only metric is the cameras' offsets D_k: an offset camera moves by (R_j - R_i) D_k
when the rig turns, which a common scaling of map and trajectory cannot mimic. The bound is
computed from the Fisher information of all observations: per landmark, the pose-landmark
blocks are reduced by the Schur complement, and the scale's variance is g^T C g for the
least-squares scale of the translations (g) and the poses' covariance C.

  scale_crlb.py run   [--seed S] [--frames F] [--life L] [--births N] [--rot X]
      a whole run: every 10 frames each camera gets N new landmarks that live L frames
  scale_crlb.py window [--seed S] [--window W] [--stride K] [--per-cam N]
      one window of W frames, keyframes every K frames, N landmarks per camera (rp_gcba's case)
  scale_crlb.py euroc --data DIR [--first F] [--frames N] [--life L] [--births N]
                      [--depth MIN MAX] [--sigma PX] [--seed S]
      a EuRoC clip's two cameras as a non-overlapping rig (issue 16): the clip's ground-truth
      body poses at cam0's stamps, each camera's T_BS and focal length; the scene is not known,
      so landmarks are drawn per camera every 10 frames at uniform pixels and depths in
      [MIN, MAX] m (default 2 5: the machine hall) and live L frames while in view

Prints the scale's standard deviation in percent. numpy (PyPI, installed into .venv by
scripts/install-deps.sh). Not a test; the figures are quoted in host_tools/research/gcdiag/README.md.
"""
import argparse

import numpy as np

FOCAL, WIDTH, HEIGHT, SIGMA = 800.0, 640, 480, 0.5


def rot(axis, a):
    c, s = np.cos(a), np.sin(a)
    if axis == 0:
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == 1:
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


CAMS = [(np.zeros(3), np.eye(3)),
        (np.array([0.0866, 0, -0.05]), rot(1, np.pi / 2)),
        (np.array([0, 0, -0.1]), rot(1, np.pi)),
        (np.array([-0.0866, 0, -0.05]), rot(1, -np.pi / 2))]


def trajectory(rng, frames, rot_scale):
    """The paper's motion: per frame +-U[5, 15] mm per axis, +-U[0.005, 0.02] rad per angle,
    R_j = R_{j-1} Rz Ry Rx."""
    d, R = [np.zeros(3)], [np.eye(3)]
    for _ in range(1, frames):
        step = rng.choice([-1.0, 1.0], 3) * rng.uniform(0.005, 0.015, 3)
        a = rot_scale * rng.choice([-1.0, 1.0], 3) * rng.uniform(0.005, 0.02, 3)
        d.append(d[-1] + step)
        R.append(R[-1] @ rot(2, a[2]) @ rot(1, a[1]) @ rot(0, a[0]))
    return np.array(d), np.array(R)


def shell_points(rng, n=10000):
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    r = rng.uniform(0.667 ** 3, 1.0, n) ** (1.0 / 3.0)
    return u * r[:, None]


def cam_point(M, d, R, k):
    D, Rk = CAMS[k]
    return (M - d - R @ D) @ R @ Rk  # rows: Rk^T R^T (M - d - R D)


def pixel(P):
    return np.stack([FOCAL * P[..., 0] / P[..., 2] + WIDTH / 2,
                     FOCAL * P[..., 1] / P[..., 2] + HEIGHT / 2], -1)


def visible(P):
    q = pixel(P)
    return (P[..., 2] > 0.05) & (q[..., 0] >= 0) & (q[..., 0] < WIDTH) & \
        (q[..., 1] >= 0) & (q[..., 1] < HEIGHT)


def hat(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def add_landmark(A, M, k, frames, d, R, col):
    """Add one landmark's reduced information to A. frames: the frames that see it; col(f):
    the first column of frame f's 6 pose parameters, or -1 for the held frame."""
    eps = 1e-6
    rows_p, rows_m = [], []
    n = A.shape[0]
    for f in frames:
        z0 = pixel(cam_point(M, d[f], R[f], k))
        Jp, Jm = np.zeros((2, n)), np.zeros((2, 3))
        c = col(f)
        for a in range(3):
            e = np.zeros(3)
            e[a] = eps
            if c >= 0:
                Jp[:, c + a] = (pixel(cam_point(M, d[f] + e, R[f], k)) - z0) / eps
                Jp[:, c + 3 + a] = (pixel(cam_point(M, d[f], (np.eye(3) + hat(e)) @ R[f], k))
                                    - z0) / eps
            Jm[:, a] = (pixel(cam_point(M + e, d[f], R[f], k)) - z0) / eps
        rows_p.append(Jp)
        rows_m.append(Jm)
    if len(rows_p) < 2:
        return 0
    Jp, Jm = np.vstack(rows_p), np.vstack(rows_m)
    nz = np.where(np.any(Jp != 0, axis=0))[0]
    Jn = Jp[:, nz]
    B = Jn.T @ Jm
    A[np.ix_(nz, nz)] += Jn.T @ Jn - B @ np.linalg.solve(Jm.T @ Jm, B.T)
    return len(rows_p)


def scale_sd(A, d, frames, col):
    C = np.linalg.inv(A / SIGMA ** 2)
    g = np.zeros(A.shape[0])
    den = sum((d[f] - d[frames[0]]) @ (d[f] - d[frames[0]]) for f in frames[1:])
    for f in frames[1:]:
        g[col(f):col(f) + 3] = (d[f] - d[frames[0]]) / den
    return float(np.sqrt(g @ C @ g))


def run_bound(a):
    rng = np.random.default_rng(a.seed)
    d, R = trajectory(rng, a.frames, a.rot)
    pts = shell_points(rng)
    A = np.zeros((6 * (a.frames - 1), 6 * (a.frames - 1)))
    col = lambda f: 6 * (f - 1) if f > 0 else -1  # noqa: E731
    nobs = nlm = 0
    for k in range(4):
        for b in range(0, a.frames - 1, 10):
            vis = np.where(visible(cam_point(pts, d[b], R[b], k)))[0]
            for i in rng.choice(vis, size=min(a.births, len(vis)), replace=False):
                seen = []
                for f in range(b, min(a.frames, b + a.life)):
                    if not visible(cam_point(pts[i], d[f], R[f], k)):
                        break
                    seen.append(f)
                got = add_landmark(A, pts[i], k, seen, d, R, col)
                nobs += got
                nlm += got > 0
    sd = scale_sd(A, d, list(range(a.frames)), col)
    print("run: %d frames, landmarks live %d frames, %d landmarks, %d observations, rotation x%g:"
          " scale sd %.2f %%" % (a.frames, a.life, nlm, nobs, a.rot, 100 * sd))


def window_bound(a):
    rng = np.random.default_rng(a.seed)
    d, R = trajectory(rng, 200, 1.0)
    pts = shell_points(rng)
    frames = list(range(50, 50 + a.window, a.stride))
    A = np.zeros((6 * (len(frames) - 1), 6 * (len(frames) - 1)))
    index = {f: i for i, f in enumerate(frames)}
    col = lambda f: 6 * (index[f] - 1) if index[f] > 0 else -1  # noqa: E731
    nobs = 0
    for k in range(4):
        chosen = []
        for f in (frames[0], frames[len(frames) // 2], frames[-1]):
            vis = np.where(visible(cam_point(pts, d[f], R[f], k)))[0]
            chosen += list(rng.choice(vis, size=min(a.per_cam // 3, len(vis)), replace=False))
        for i in chosen:
            seen = [f for f in frames if visible(cam_point(pts[i], d[f], R[f], k))]
            nobs += add_landmark(A, pts[i], k, seen, d, R, col)
    sd = scale_sd(A, d, frames, col)
    print("window: %d frames, keyframes every %d, %d landmarks per camera, %d observations:"
          " scale sd %.2f %%" % (a.window, a.stride, a.per_cam, nobs, 100 * sd))


def euroc_rig(data):
    """cam0's and cam1's (position, rotation) in the body frame (T_BS) and their focal lengths,
    image size from cam0."""
    cams, focal = [], []
    for c in ("cam0", "cam1"):
        txt = open("%s/%s/sensor.yaml" % (data, c)).read()
        blk = txt[txt.index("T_BS"):]
        vals = blk[blk.index("[") + 1:blk.index("]")].replace("\n", " ").split(",")
        T = np.array([float(v) for v in vals]).reshape(4, 4)
        cams.append((T[:3, 3], T[:3, :3]))
        intr = txt[txt.index("intrinsics:"):]
        fu = float(intr[intr.index("[") + 1:intr.index("]")].split(",")[0])
        focal.append(fu)
        if c == "cam0":
            res = txt[txt.index("resolution:"):]
            w, h = [int(v) for v in res[res.index("[") + 1:res.index("]")].split(",")]
    return cams, float(np.mean(focal)), w, h


def quat_R(qx, qy, qz, qw):
    return np.array([[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
                     [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
                     [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]])


def euroc_bound(a):
    global CAMS, FOCAL, WIDTH, HEIGHT, SIGMA
    CAMS, FOCAL, WIDTH, HEIGHT = euroc_rig(a.data)
    SIGMA = a.sigma
    stamps = [int(l.split(",")[0]) * 1e-9 for l in open("%s/cam0/data.csv" % a.data)
              if l[0].isdigit()][a.first:a.first + a.frames]
    gt = np.array([[float(v) for v in l.split()] for l in open("%s/groundtruth.txt" % a.data)
                   if l[0].isdigit()])
    d, R = [], []
    for t in stamps:
        g = gt[np.argmin(np.abs(gt[:, 0] - t))]
        d.append(g[1:4])
        R.append(quat_R(*g[4:8]))
    d, R = np.array(d), np.array(R)
    # the first frame's body pose is the world (held); positions relative to it
    R0 = R[0].copy()
    d = (d - d[0]) @ R0
    R = np.array([R0.T @ Rf for Rf in R])
    n = len(stamps)
    rng = np.random.default_rng(a.seed)
    A = np.zeros((6 * (n - 1), 6 * (n - 1)))
    col = lambda f: 6 * (f - 1) if f > 0 else -1  # noqa: E731
    nobs = nlm = 0
    for k in range(len(CAMS)):
        Dk, Rk = CAMS[k]
        for b in range(0, n - 1, 10):
            for _ in range(a.births):
                u, v = rng.uniform(0, WIDTH), rng.uniform(0, HEIGHT)
                z = rng.uniform(a.depth[0], a.depth[1])
                Pc = np.array([(u - WIDTH / 2) / FOCAL * z, (v - HEIGHT / 2) / FOCAL * z, z])
                M = d[b] + R[b] @ (Dk + Rk @ Pc)
                seen = []
                for f in range(b, min(n, b + a.life)):
                    if not visible(cam_point(M, d[f], R[f], k)):
                        break
                    seen.append(f)
                got = add_landmark(A, M, k, seen, d, R, col)
                nobs += got
                nlm += got > 0
    path = float(np.sum(np.linalg.norm(np.diff(d, axis=0), axis=1)))
    ang = [np.degrees(np.arccos(np.clip((np.trace(R[f - 1].T @ R[f]) - 1) / 2, -1, 1)))
           for f in range(1, n)]
    sd = scale_sd(A, d, list(range(n)), col)
    print("euroc: frames %d-%d, %d cameras %.3f m apart, focal %.1f px, sigma %.2f px, path "
          "%.2f m, rotation %.1f deg/frame mean; %d landmarks at %g-%g m living %d frames, %d "
          "observations: scale sd %.2f %%" % (a.first, a.first + n - 1, len(CAMS),
                                              float(np.linalg.norm(CAMS[1][0] - CAMS[0][0])),
                                              FOCAL, SIGMA, path, float(np.mean(ang)), nlm,
                                              a.depth[0], a.depth[1], a.life, nobs, 100 * sd))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="mode", required=True)
    r = sub.add_parser("run")
    r.add_argument("--seed", type=int, default=1)
    r.add_argument("--frames", type=int, default=100)
    r.add_argument("--life", type=int, default=29)
    r.add_argument("--births", type=int, default=50)
    r.add_argument("--rot", type=float, default=1.0)
    w = sub.add_parser("window")
    w.add_argument("--seed", type=int, default=1)
    w.add_argument("--window", type=int, default=24)
    w.add_argument("--stride", type=int, default=4)
    w.add_argument("--per-cam", type=int, default=80)
    e = sub.add_parser("euroc")
    e.add_argument("--data", required=True)
    e.add_argument("--first", type=int, default=0)
    e.add_argument("--frames", type=int, default=150)
    e.add_argument("--life", type=int, default=29)
    e.add_argument("--births", type=int, default=50)
    e.add_argument("--depth", type=float, nargs=2, default=[2.0, 5.0])
    e.add_argument("--sigma", type=float, default=0.5)
    e.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    {"run": run_bound, "window": window_bound, "euroc": euroc_bound}[a.mode](a)


if __name__ == "__main__":
    main()
