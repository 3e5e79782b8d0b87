#!/usr/bin/python3
"""A plain vectorised numpy solver of the global weight-space GP model.

The peer that rff_slam's speed is compared against (bench/compare/README.md):
the MAP of one global feature map per coordinate,

    x_k(t) = m_k(t) + phi(t)^T b_k,  b_k ~ N(0, I),  k = x, y, theta,

with phi the Hilbert basis of an RBF kernel (Solin and Saerkkae 2020, eq. 56:
phi_j(t) = sqrt(S(w_j) / L) sin(w_j (t - c + L)), w_j = pi j / (2 L)), m the
dead reckoning from the first pose prior (the constant first pose when there
is no odometry), and range, bearing, odometry, pose-prior and landmark-prior
residuals whitened by their sigmas. Levenberg-Marquardt on the dense normal
equations, stopped like Ceres at a relative cost change of 1e-8.

Usage: numpy_dense_lm.py DATASET.rffd [--num_features=100] [--lengthscale=5]
       [--kernel_variance=100] [--heading_kernel_variance=0.25]
Prints one JSON line: solve seconds, iterations, final cost, APE.
"""
import argparse
import json
import sys
import time

import numpy as np


def read_rffd(path):
    """The records the model uses, as float arrays, in file order."""
    records = {}
    with open(path, encoding="utf-8") as f:
        for line in f:
            fields = line.split("#", 1)[0].split()
            if not fields or fields[0] == "RFFD":
                continue
            records.setdefault(fields[0], []).append([float(v) for v in fields[1:]])
    for kind in ("RANGE", "BEARING"):
        if kind in records:
            sys.exit(f"{path}: {kind} records are outside this peer's model")
    if any(k not in records
           for k in ("PRIOR_POSE", "PRIOR_LANDMARK", "RANGE_BEARING")):
        sys.exit(f"{path}: needs PRIOR_POSE, PRIOR_LANDMARK and RANGE_BEARING "
                 "records")
    data = {k: np.array(v) for k, v in records.items()}
    unknown = set(data["RANGE_BEARING"][:, 1]) - set(data["PRIOR_LANDMARK"][:, 0])
    if unknown:
        sys.exit(f"{path}: landmark {int(min(unknown))} is observed but has no "
                 "PRIOR_LANDMARK, which this peer needs")
    return data


def wrap(a):
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def dead_reckoning(prior, odom, times):
    """The first pose prior composed with the ODOM records, at `times`."""
    pose = prior[1:4].copy()
    if odom is None:
        return np.tile(pose, (len(times), 1))
    knots, poses = [prior[0]], [pose.copy()]
    for t0, t1, dx, dy, dth, *_ in odom:
        c, s = np.cos(pose[2]), np.sin(pose[2])
        pose = pose + np.array([c * dx - s * dy, s * dx + c * dy, dth])
        knots.append(t1)
        poses.append(pose.copy())
    poses = np.array(poses)
    return np.stack([np.interp(times, knots, poses[:, k]) for k in range(3)], 1)


def hilbert_features(times, num_features, lengthscale, variance):
    begin, end = times.min(), times.max()
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
        rb = data["RANGE_BEARING"]
        self.prior = data["PRIOR_POSE"][0]
        odom = data.get("ODOM")
        times = [rb[:, 0], self.prior[:1]]
        if odom is not None:
            times += [odom[:, 0], odom[:, 1]]
        self.times = np.unique(np.concatenate(times))
        self.mean = dead_reckoning(self.prior, odom, self.times)
        n = args.num_features
        phi_xy = hilbert_features(self.times, n, args.lengthscale,
                                  args.kernel_variance)
        phi_th = hilbert_features(self.times, n, args.lengthscale,
                                  args.heading_kernel_variance)
        self.phi = [phi_xy, phi_xy, phi_th]
        self.n = n
        lm = data["PRIOR_LANDMARK"]
        self.ids = {int(i): k for k, i in enumerate(lm[:, 0])}
        self.lm_prior, self.lm_sigma = lm[:, 1:3], lm[:, 3]
        index = lambda t: np.searchsorted(self.times, t)
        self.obs_pose = index(rb[:, 0])
        self.obs_lm = np.array([self.ids[int(i)] for i in rb[:, 1]])
        self.obs = rb[:, 2:4]
        self.obs_sigma = rb[:, 4:6]
        self.odom = odom
        if odom is not None:
            self.odom_from, self.odom_to = index(odom[:, 0]), index(odom[:, 1])
        self.prior_index = index(self.prior[:1])[0]
        self.num_weights = 3 * n
        self.num_params = 3 * n + 2 * len(self.ids)

    def poses(self, params):
        b = params[: self.num_weights].reshape(3, self.n)
        return self.mean + np.stack([self.phi[k] @ b[k] for k in range(3)], 1)

    def linearize(self, params):
        """Whitened residuals and their dense Jacobian."""
        n, nw = self.n, self.num_weights
        poses = self.poses(params)
        lms = params[nw:].reshape(-1, 2)
        blocks_r, blocks_j = [], []

        def pose_rows(d_pose, at):
            # d r / d b_k = d r / d pose_k * phi_k(t): one dense row band.
            j = np.zeros((d_pose.shape[0], self.num_params))
            for k in range(3):
                j[:, k * n:(k + 1) * n] += d_pose[:, k, None] * self.phi[k][at]
            return j

        # Range and bearing.
        p, l = poses[self.obs_pose], lms[self.obs_lm]
        d = l - p[:, :2]
        r2 = (d ** 2).sum(1)
        r = np.sqrt(r2)
        s_r, s_b = self.obs_sigma[:, 0], self.obs_sigma[:, 1]
        res_r = (r - self.obs[:, 0]) / s_r
        res_b = wrap(np.arctan2(d[:, 1], d[:, 0]) - p[:, 2] - self.obs[:, 1]) / s_b
        dr_dl = d / r[:, None] / s_r[:, None]
        db_dl = np.stack([-d[:, 1], d[:, 0]], 1) / r2[:, None] / s_b[:, None]
        zeros = np.zeros_like(r)
        j_r = pose_rows(np.stack([-dr_dl[:, 0], -dr_dl[:, 1], zeros], 1),
                        self.obs_pose)
        j_b = pose_rows(np.stack([-db_dl[:, 0], -db_dl[:, 1], -1 / s_b], 1),
                        self.obs_pose)
        cols = nw + 2 * self.obs_lm
        rows = np.arange(len(r))
        for c in range(2):
            j_r[rows, cols + c] = dr_dl[:, c]
            j_b[rows, cols + c] = db_dl[:, c]
        blocks_r += [res_r, res_b]
        blocks_j += [j_r, j_b]

        # Odometry: the motion from t0 to t1 in the frame of the pose at t0.
        if self.odom is not None:
            a, b = poses[self.odom_from], poses[self.odom_to]
            sig = self.odom[:, 5:8]
            c, s = np.cos(a[:, 2]), np.sin(a[:, 2])
            dx, dy = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
            pred = np.stack([c * dx + s * dy, -s * dx + c * dy,
                             wrap(b[:, 2] - a[:, 2])], 1)
            res = (pred - self.odom[:, 2:5])
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
                d_a = -d_b.copy()
                d_a[:, 2] = d_th if row < 2 else -1.0
                blocks_r.append(res[:, row])
                blocks_j.append((pose_rows(d_a, self.odom_from) +
                                 pose_rows(d_b, self.odom_to)) / sig[:, row, None])

        # First-pose prior, landmark priors, weight prior.
        sig = np.array([self.prior[4], self.prior[4], self.prior[5]])
        res = poses[self.prior_index] - self.prior[1:4]
        res[2] = wrap(res[2])
        blocks_r.append(res / sig)
        blocks_j.append(pose_rows(np.diag(1 / sig),
                                  np.full(3, self.prior_index)))
        res = ((lms - self.lm_prior) / self.lm_sigma[:, None]).ravel()
        j = np.zeros((res.size, self.num_params))
        j[:, nw:] = np.diag(np.repeat(1 / self.lm_sigma, 2))
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
    data = read_rffd(args.dataset)
    start = time.perf_counter()
    model = Model(data, args)
    params = np.zeros(model.num_params)
    params[model.num_weights:] = model.lm_prior.ravel()
    params, cost, iterations = levenberg_marquardt(model, params)
    seconds = time.perf_counter() - start
    ape = None
    if "GT_POSE" in data:
        truth = data["GT_POSE"]
        poses = model.poses(params)
        est = np.stack([np.interp(truth[:, 0], model.times, poses[:, k])
                        for k in range(2)], 1)
        ape = float(np.sqrt(((est - truth[:, 1:3]) ** 2).sum(1).mean()))
    print(json.dumps({"seconds": seconds, "iterations": iterations,
                      "final_cost": cost, "ape_trans_m": ape,
                      "num_parameters": model.num_params}))


if __name__ == "__main__":
    main()
