#!/usr/bin/python3
"""A plain vectorised numpy solver of the global weight-space GP model.

The peer that rff_slam's speed is compared against (bench/compare/README.md):
the MAP of one global feature map per coordinate,

    x_k(t) = m_k(t) + delta g_k(t) + phi(t)^T b_k,  b_k ~ N(0, I),

with phi the Hilbert basis of an RBF kernel (Solin and Saerkkae 2020, eq. 56:
phi_j(t) = sqrt(S(w_j) / L) sin(w_j (t - c + L)), w_j = pi j / (2 L)), m the
dead reckoning from the earliest pose prior, delta g(t) its rotation about
that pose to first order (rff_ceres/mean_rotation.h), and range-bearing,
odometry, pose-prior and landmark-prior residuals whitened by their sigmas.
A range-bearing record closer than two range sigmas is its landmark's offset
along and across the measured ray (costs/near_landmark_cost.h). That is the
model rff_slam solves with compare.SAME_MODEL_FLAGS. Levenberg-Marquardt on
the dense normal equations, stopped like Ceres at a relative cost change of
1e-8.

Usage: numpy_dense_lm.py DATASET.rffd [--num_features=100] [--lengthscale=5]
       [--kernel_variance=100] [--heading_kernel_variance=0.25]
Prints one JSON line: solve seconds, iterations, final cost, APE. A file
that rff_slam would refuse or model differently (no odometry, RANGE or
BEARING records, gaps that rff_slam would split the run at, a loose start
heading, bad values) is refused with a message and exit status 1
(bench/compare/README.md lists the cases).
"""
import argparse
import json
import sys
import time

import numpy as np

FIELDS = {"PRIOR_POSE": 6, "PRIOR_LANDMARK": 4, "ODOM": 8, "RANGE_BEARING": 6,
          "GT_POSE": 4, "GT_LANDMARK": 3, "RANGE": 4, "BEARING": 4}
NEAR_RANGE_SIGMAS = 2.0  # costs/near_landmark_cost.h, kNearRangeSigmas.
LOOSE_HEADING_SIGMA = 0.5  # rff_ceres/initialization.h, kLooseHeadingSigma.
MAX_GAP_LENGTHSCALES = 10.0  # rff_slam splits a run at longer gaps.


def fail(message):
    sys.exit(f"numpy_dense_lm.py: {message}")


SIGMAS = {"PRIOR_POSE": (4, 5), "PRIOR_LANDMARK": (3,), "ODOM": (5, 6, 7),
          "RANGE_BEARING": (4, 5)}
IDS = {"PRIOR_LANDMARK": 0, "RANGE_BEARING": 1, "GT_LANDMARK": 0}


def read_rffd(path):
    """The records as float arrays (observations and odometry in time order,
    pose priors in file order); fails on anything rff_slam would refuse."""
    records = {}
    try:
        with open(path, encoding="utf-8") as f:
            lines = f.readlines()
    except (OSError, UnicodeDecodeError) as e:
        fail(f"{path}: cannot read: {e}")
    header = False
    for number, line in enumerate(lines, 1):
        fields = line.split("#", 1)[0].split()
        if not fields:
            continue
        where = f"{path}:{number}"
        if not header:
            if fields != ["RFFD", "1"]:
                fail(f"{where}: the first record must be the header RFFD 1")
            header = True
            continue
        kind = fields[0]
        if kind in ("RANGE", "BEARING"):
            fail(f"{where}: {kind} records are outside this peer's model")
        if kind not in FIELDS or len(fields) != FIELDS[kind] + 1:
            fail(f"{where}: not a record this peer reads: {line.strip()}")
        try:
            values = [float(v) for v in fields[1:]]
        except ValueError:
            fail(f"{where}: a field is not a number: {line.strip()}")
        if not all(np.isfinite(values)):
            fail(f"{where}: a field is not a finite number: {line.strip()}")
        if any(values[i] <= 0 for i in SIGMAS.get(kind, ())):
            fail(f"{where}: a sigma is not positive: {line.strip()}")
        if kind in IDS:
            i = values[IDS[kind]]
            if i != int(i) or not 0 <= i < 2**31:
                fail(f"{where}: a landmark id must be a non-negative integer: "
                     f"{line.strip()}")
        if kind == "ODOM" and not values[1] > values[0]:
            fail(f"{where}: t1 must be after t0: {line.strip()}")
        records.setdefault(kind, []).append(values)
    for kind in ("PRIOR_POSE", "PRIOR_LANDMARK", "RANGE_BEARING", "ODOM"):
        if kind not in records:
            fail(f"{path}: needs {kind} records (the peer's mean is the dead "
                 "reckoning, and every landmark needs a prior)")
    data = {k: np.array(v if k == "PRIOR_POSE" else sorted(v))
            for k, v in records.items()}
    for kind, column, what in (("PRIOR_LANDMARK", 0, "landmark prior"),
                               ("GT_POSE", 0, "GT_POSE time")):
        if kind in data and len(np.unique(data[kind][:, column])) < len(data[kind]):
            fail(f"{path}: a duplicate {what}")
    unknown = set(data["RANGE_BEARING"][:, 1]) - set(data["PRIOR_LANDMARK"][:, 0])
    if unknown:
        fail(f"{path}: landmark {int(min(unknown))} is observed but has no "
             "PRIOR_LANDMARK")
    return data


def wrap(a):
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def dead_reckoning(prior, odom, path):
    """Knot times and poses of the ODOM chain from the pose prior `prior`."""
    if odom[0, 0] != prior[0] or np.any(odom[1:, 0] != odom[:-1, 1]):
        fail(f"{path}: the ODOM records must form one chain starting at the "
             "earliest PRIOR_POSE")
    pose = prior[1:4].copy()
    knots, poses = [prior[0]], [pose.copy()]
    for _, t1, dx, dy, dth, *_ in odom:
        c, s = np.cos(pose[2]), np.sin(pose[2])
        pose = pose + np.array([c * dx - s * dy, s * dx + c * dy, dth])
        knots.append(t1)
        poses.append(pose.copy())
    return np.array(knots), np.array(poses)


def hilbert_features(times, window, num_features, lengthscale, variance):
    begin, end = window
    half = 0.5 * (end - begin)
    half_width = half + max(0.1 * half, 4.0 * lengthscale)
    w = np.pi * np.arange(1, num_features + 1) / (2.0 * half_width)
    # RBF spectral density S(w) = s^2 sqrt(2 pi) l exp(-w^2 l^2 / 2).
    density = variance * np.sqrt(2 * np.pi) * lengthscale * np.exp(
        -0.5 * (w * lengthscale) ** 2)
    amplitude = np.sqrt(density / half_width)
    x = times - 0.5 * (begin + end) + half_width
    return amplitude * np.sin(np.outer(x, w))


class Model:
    def __init__(self, data, args):
        rb, odom = data["RANGE_BEARING"], data["ODOM"]
        path = args.dataset
        self.priors = data["PRIOR_POSE"]
        first = self.priors[np.argmin(self.priors[:, 0])]  # First in the file.
        if first[5] > LOOSE_HEADING_SIGMA:
            fail(f"{path}: a start heading sigma above {LOOSE_HEADING_SIGMA} "
                 "rad, which rff_slam re-estimates first and this peer does "
                 "not")
        self.times = np.unique(np.concatenate(
            [rb[:, 0], self.priors[:, 0], odom[:, 0], odom[:, 1]]))
        # Gaps between what the data cover: an ODOM record covers [t0, t1].
        starts = np.concatenate([rb[:, 0], self.priors[:, 0], odom[:, 0]])
        ends = np.concatenate([rb[:, 0], self.priors[:, 0], odom[:, 1]])
        order = np.argsort(starts, kind="stable")
        covered = np.maximum.accumulate(ends[order])
        gaps = starts[order][1:] - covered[:-1]
        max_gap = MAX_GAP_LENGTHSCALES * args.lengthscale
        if gaps.size and gaps.max() > max_gap:
            fail(f"{path}: a gap of {gaps.max():g} s in the data: rff_slam "
                 "would split the run there, this peer has one global map")
        # The window spans the data and the ground truth within max_gap of it.
        begin, end = self.times.min(), self.times.max()
        if "GT_POSE" in data:
            gt = data["GT_POSE"][:, 0]
            gt = gt[(gt >= begin - max_gap) & (gt <= end + max_gap)]
            begin, end = min(begin, gt.min(initial=begin)), max(
                end, gt.max(initial=end))
        self.window = (begin, end)
        self.knots, self.knot_poses = dead_reckoning(first, odom, path)
        self.anchor = self.mean_at(first[:1])[0]
        self.delta_sigma = min(first[5], LOOSE_HEADING_SIGMA)
        self.args = args
        self.n = n = args.num_features
        self.phi, self.mean, self.rotation = self.basis(self.times)
        lm = data["PRIOR_LANDMARK"]
        self.ids = {int(i): k for k, i in enumerate(lm[:, 0])}
        self.lm_prior, self.lm_sigma = lm[:, 1:3], lm[:, 3]
        index = lambda t: np.searchsorted(self.times, t)
        self.obs_pose = index(rb[:, 0])
        self.obs_lm = np.array([self.ids[int(i)] for i in rb[:, 1]])
        self.obs = rb[:, 2:4]
        self.obs_sigma = rb[:, 4:6]
        self.near = self.obs[:, 0] < NEAR_RANGE_SIGMAS * self.obs_sigma[:, 0]
        self.odom = odom
        self.odom_from, self.odom_to = index(odom[:, 0]), index(odom[:, 1])
        self.prior_index = index(self.priors[:, 0])
        # Parameters: 3 n weights, the mean's turn delta, the landmarks.
        self.num_weights = 3 * n
        self.delta = 3 * n
        self.num_params = 3 * n + 1 + 2 * len(self.ids)

    def mean_at(self, times):
        return np.stack([np.interp(times, self.knots, self.knot_poses[:, k])
                         for k in range(3)], 1)

    def basis(self, times):
        """Features per coordinate, the mean and the turn's g(t) at `times`."""
        a = self.args
        phi_xy = hilbert_features(times, self.window, a.num_features,
                                  a.lengthscale, a.kernel_variance)
        phi_th = hilbert_features(times, self.window, a.num_features,
                                  a.lengthscale, a.heading_kernel_variance)
        mean = self.mean_at(times)
        arm = mean[:, :2] - self.anchor[:2]
        rotation = np.stack([-arm[:, 1], arm[:, 0], np.ones(len(times))], 1)
        return [phi_xy, phi_xy, phi_th], mean, rotation

    def poses(self, params, basis=None):
        phi, mean, rotation = basis or (self.phi, self.mean, self.rotation)
        b = params[: self.num_weights].reshape(3, self.n)
        return (mean + params[self.delta] * rotation +
                np.stack([phi[k] @ b[k] for k in range(3)], 1))

    def pose_rows(self, d_pose, at):
        """d r / d (b, delta) from d r / d pose at the model times `at`."""
        n = self.n
        j = np.zeros((d_pose.shape[0], self.num_params))
        for k in range(3):
            j[:, k * n:(k + 1) * n] = d_pose[:, k, None] * self.phi[k][at]
        j[:, self.delta] = (d_pose * self.rotation[at]).sum(1)
        return j

    def observation_rows(self, poses, lms):
        """Two rows per range-bearing record: residuals, d/dpose, d/dlandmark."""
        p, l = poses[self.obs_pose], lms[self.obs_lm]
        s_r, s_b = self.obs_sigma[:, 0], self.obs_sigma[:, 1]
        z_r, z_b = self.obs[:, 0], self.obs[:, 1]
        d = l - p[:, :2]
        r2 = (d ** 2).sum(1)
        r = np.sqrt(r2)
        res = np.stack([(r - z_r) / s_r,
                        wrap(np.arctan2(d[:, 1], d[:, 0]) - p[:, 2] - z_b) / s_b])
        d_lm = np.stack([d / (r * s_r)[:, None],
                         np.stack([-d[:, 1], d[:, 0]], 1) / (r2 * s_b)[:, None]])
        d_pose = np.concatenate(
            [-d_lm, np.stack([np.zeros_like(r), -1 / s_b])[:, :, None]], 2)
        # Near records: q = R(theta)^T (l - p) along and across the ray.
        c, s = np.cos(p[:, 2]), np.sin(p[:, 2])
        rt = np.stack([np.stack([c, s], 1), np.stack([-s, c], 1)], 1)
        q = np.einsum("mij,mj->mi", rt, d)
        across = np.hypot(z_r, s_r) * s_b
        ray = np.stack([np.cos(z_b), np.sin(z_b)], 1)
        whitening = np.stack([ray / s_r[:, None],
                              np.stack([-ray[:, 1], ray[:, 0]], 1) /
                              across[:, None]])
        near_res = np.einsum("rmi,mi->rm", whitening, q)
        near_res[0] -= z_r / s_r
        near_lm = np.einsum("rmi,mij->rmj", whitening, rt)
        dq_dth = np.stack([q[:, 1], -q[:, 0]], 1)
        near_pose = np.concatenate(
            [-near_lm, np.einsum("rmi,mi->rm", whitening, dq_dth)[:, :, None]],
            2)
        near = self.near[None, :]
        return (np.where(near, near_res, res),
                np.where(near[:, :, None], near_pose, d_pose),
                np.where(near[:, :, None], near_lm, d_lm))

    def linearize(self, params):
        """Whitened residuals and their dense Jacobian."""
        nw = self.num_weights
        poses = self.poses(params)
        lms = params[nw + 1:].reshape(-1, 2)
        blocks_r, blocks_j = [], []

        res, d_pose, d_lm = self.observation_rows(poses, lms)
        cols = nw + 1 + 2 * self.obs_lm
        rows = np.arange(len(cols))
        for row in range(2):
            j = self.pose_rows(d_pose[row], self.obs_pose)
            for c in range(2):
                j[rows, cols + c] = d_lm[row, :, c]
            blocks_r.append(res[row])
            blocks_j.append(j)

        # Odometry: the motion from t0 to t1 in the frame of the pose at t0.
        a, b = poses[self.odom_from], poses[self.odom_to]
        sig = self.odom[:, 5:8]
        c, s = np.cos(a[:, 2]), np.sin(a[:, 2])
        dx, dy = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
        pred = np.stack([c * dx + s * dy, -s * dx + c * dy, b[:, 2] - a[:, 2]], 1)
        res = pred - self.odom[:, 2:5]
        res[:, 2] = wrap(res[:, 2])
        res /= sig
        for row in range(3):
            d_b = np.zeros((len(c), 3))
            if row == 0:
                d_b[:, 0], d_b[:, 1] = c, s
                d_th = -s * dx + c * dy
            elif row == 1:
                d_b[:, 0], d_b[:, 1] = -s, c
                d_th = -c * dx - s * dy
            else:
                d_b[:, 2] = 1.0
                d_th = -np.ones_like(c)
            d_a = -d_b
            d_a[:, 2] = d_th
            blocks_r.append(res[:, row])
            blocks_j.append((self.pose_rows(d_a, self.odom_from) +
                             self.pose_rows(d_b, self.odom_to)) /
                            sig[:, row, None])

        # Pose priors, the turn's prior, landmark priors, weight prior.
        sig = self.priors[:, [4, 4, 5]]
        res = poses[self.prior_index] - self.priors[:, 1:4]
        res[:, 2] = wrap(res[:, 2])
        res /= sig
        for row in range(3):
            d_pose = np.zeros((len(sig), 3))
            d_pose[:, row] = 1.0 / sig[:, row]
            blocks_r.append(res[:, row])
            blocks_j.append(self.pose_rows(d_pose, self.prior_index))
        j = np.zeros((1, self.num_params))
        j[0, self.delta] = 1.0 / self.delta_sigma
        blocks_r.append(params[self.delta:self.delta + 1] / self.delta_sigma)
        blocks_j.append(j)
        res = ((lms - self.lm_prior) / self.lm_sigma[:, None]).ravel()
        j = np.zeros((res.size, self.num_params))
        j[:, nw + 1:] = np.diag(np.repeat(1 / self.lm_sigma, 2))
        blocks_r += [res, params[:nw]]
        blocks_j += [j, np.eye(nw, self.num_params)]
        return np.concatenate(blocks_r), np.vstack(blocks_j)


def levenberg_marquardt(model, params, max_iterations=100, tolerance=1e-8):
    res, jac = model.linearize(params)
    cost = 0.5 * res @ res
    radius = 1e4  # Ceres's initial trust region radius.
    iterations = 0
    for iterations in range(1, max_iterations + 1):
        g = jac.T @ res
        h = jac.T @ jac
        diag = np.clip(np.diag(h), 1e-6, 1e32)
        step = np.linalg.solve(h + np.diag(diag / radius), -g)
        new_res, new_jac = model.linearize(params + step)
        new_cost = 0.5 * new_res @ new_res
        predicted = -(g @ step + 0.5 * step @ (h @ step))
        if new_cost < cost:
            change = cost - new_cost
            params, res, jac, cost = params + step, new_res, new_jac, new_cost
            rho = change / max(predicted, 1e-300)
            radius /= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
            if change <= tolerance * (cost + change):
                break
        else:
            radius /= 2.0
    return params, cost, iterations


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dataset")
    parser.add_argument("--num_features", type=int, default=100)
    parser.add_argument("--lengthscale", type=float, default=5.0)
    parser.add_argument("--kernel_variance", type=float, default=100.0)
    parser.add_argument("--heading_kernel_variance", type=float, default=0.25)
    args = parser.parse_args()
    values = (args.lengthscale, args.kernel_variance,
              args.heading_kernel_variance)
    if args.num_features < 1 or not all(0 < v < np.inf for v in values):
        fail("--num_features must be 1 or more and the kernel's values finite "
             "and more than 0")
    data = read_rffd(args.dataset)
    start = time.perf_counter()
    model = Model(data, args)
    params = np.zeros(model.num_params)
    params[model.num_weights + 1:] = model.lm_prior.ravel()
    params, cost, iterations = levenberg_marquardt(model, params)
    seconds = time.perf_counter() - start
    # rff_slam turns the mean exactly and solves again past this error.
    delta = params[model.delta]
    second_order = (np.array([[np.cos(delta) - 1, -np.sin(delta) + delta],
                              [np.sin(delta) - delta, np.cos(delta) - 1]]))
    arms = model.mean[:, :2] - model.anchor[:2]
    if np.linalg.norm(arms @ second_order.T, axis=1).max() > 0.01:
        fail(f"{args.dataset}: the mean turned by {delta:g} rad, beyond its "
             "first-order form, where rff_slam turns it exactly and solves "
             "again")
    ape = None
    if "GT_POSE" in data:
        truth = data["GT_POSE"]
        poses = model.poses(params, model.basis(truth[:, 0]))
        ape = float(np.sqrt(((poses[:, :2] - truth[:, 1:3]) ** 2).sum(1).mean()))
    print(json.dumps({"seconds": seconds, "iterations": iterations,
                      "final_cost": cost, "ape_trans_m": ape,
                      "num_parameters": model.num_params}))


if __name__ == "__main__":
    main()
