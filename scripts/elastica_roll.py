#!/usr/bin/env python3
"""Independent reference for a strip rolled by an end moment past a full turn: the planar
elastica with self-contact at an offset, solved here (numpy only, none of shellsim's code),
compared with a shellsim run's last frame.

    elastica_roll.py OUT_DIR REFERENCE_MESH --length L --thickness H --young E --poisson NU
                     --moment M [--segments N] [--steps S] [--json FILE]

The strip is an inextensible Euler elastica of bending stiffness D = E h³/(12(1 − ν²)) per
unit width, clamped at arc length s = 0 with its tangent along +x, loaded at s = L by the end
moment M per unit width (`loads.moment`), rolling in the x–z plane. It is cut into N
straight segments of angles θ_i; the energy per unit width is

    D/Δs θ_0² / 2  +  Σ_(i≥1) D/(2Δs) (θ_i − θ_{i−1})²  −  M θ_{N−1}  +  Σ_(node j, segment i) k Δs (h − d_ji)₊² / 2,

with θ_i the tangent at the middle of segment i (so the clamp's θ(0) = 0 is half a segment
before θ_0) and d_ji the distance from node j to segment i, for every pair
more than 3h apart along the strip. The penalty k = M/(2 h² Δs) lets the layers sink about
h/100 into each other (the shell's own law, about h/250): the layers' centrelines stay h apart,
as the shell's mid-surfaces do. The moment is applied in S equal steps (the shell's continuation) and each step is solved
by Newton's method on the exact gradient, with a Gauss–Newton contact Hessian, a diagonal
shift while it is not positive definite and a backtracking line search on the energy, to a
gradient 1e-8 of the moment (or a Newton step below 1e-13 rad,
round-off's floor).

The comparison uses the two curves' tangent angle θ(s) and position r(s) along the arc length
(the shell's centreline is the mean of its mesh's vertices across the width, at each station
along x in the reference mesh):

* the **turns' radii**: the mean radius of curvature of each turn, arc length over angle. The
  first turn runs from the clamp to θ = 2π, the second on to the tip. With more than a full turn
  the tip winds inside the first turn, so the spiral's turns counted from the inside are the
  second turn (r_0) and the first (r_1);
* the largest distance between the two centrelines at equal arc length, over r_0;
* the gap between the layers where the tip's turn lies over the first (the distance from each
  point of the tip's turn within 2h of the first turn to that turn): its smallest, median and
  largest value. Where the layers touch it is h, so the spiral's turns at the same angle are
  r_1 = r_0 + gap; the mean radii differ by less than h because the first turn's free half is
  wider.

The reference's own spread: 150 and 300 segments give radii within 5e-5 of each other; 200 and
600 find a neighbouring equilibrium whose radii are 0.2%
larger. A shell mesh with edges of h/2 is 0.25% below the 150-segment radii, and its gaps' smallest,
median and largest values match the reference's to 0.6%.

Prints the numbers and writes them as JSON with --json.
"""

import argparse
import glob
import json
import os

import numpy as np


def solve(L, h, D, M, n, steps):
    ds = L / n
    s_mid = (np.arange(n) + 0.5) * ds
    s_node = np.arange(n + 1) * ds
    # Node j against segment i: excluded within 3h along the strip (both ends of the segment).
    near = (np.abs(s_node[:, None] - s_node[None, :-1]) < 3 * h) | (
        np.abs(s_node[:, None] - s_node[None, 1:]) < 3 * h
    )
    # The clamped node 0 is a node like any other; the segments are i = 0..n-1.
    # A node pressed by a force F per unit width sinks F/(k Δs): about h/100 here (8e-5 at
    # h = 0.01), which shifts the radii by 0.1%. A stiffer penalty lets the ripple of the polyline (Δs²/8r) trap
    # sliding contacts, and the solution then depends on the load steps.
    k = 0.5 * M / (h * h * ds)
    theta = np.zeros(n)

    def positions(th):
        x = np.zeros((n + 1, 2))
        x[1:, 0] = np.cumsum(ds * np.cos(th))
        x[1:, 1] = np.cumsum(ds * np.sin(th))
        return x

    def contact(x, with_derivatives=True):
        """Energy, gradient in x (n+1, 2) and Gauss–Newton Hessian in x ((2n+2)²)."""
        a = x[:-1]
        e = x[1:] - x[:-1]
        l2 = np.einsum("ij,ij->i", e, e)
        rel = x[:, None, :] - a[None, :, :]
        t = np.clip(np.einsum("jik,ik->ji", rel, e) / l2[None, :], 0.0, 1.0)
        diff = rel - t[:, :, None] * e[None, :, :]
        d = np.linalg.norm(diff, axis=2)
        act = (~near) & (d < h)
        jj, ii = np.nonzero(act)
        pen = h - d[jj, ii]
        energy = 0.5 * k * ds * np.dot(pen, pen)
        if not with_derivatives:
            return energy, None, None
        nrm = diff[jj, ii] / d[jj, ii][:, None]
        tt = t[jj, ii]
        # The three nodes of each pair and the weights of d's gradient on them.
        nodes = np.stack([jj, ii, ii + 1], axis=1)
        w = np.stack([np.ones_like(tt), -(1.0 - tt), -tt], axis=1)
        g = np.zeros((n + 1, 2))
        for c in range(3):
            np.add.at(g, nodes[:, c], (-k * ds * pen * w[:, c])[:, None] * nrm)
        H = np.zeros((2 * n + 2, 2 * n + 2))
        nn = np.einsum("pi,pj->pij", nrm, nrm) * (k * ds)
        for a_ in range(3):
            for b_ in range(3):
                blk = (w[:, a_] * w[:, b_])[:, None, None] * nn
                for r_ in range(2):
                    for c_ in range(2):
                        np.add.at(
                            H,
                            (2 * nodes[:, a_] + r_, 2 * nodes[:, b_] + c_),
                            blk[:, r_, c_],
                        )
        return energy, g, H

    def energy_only(th, m):
        dth = np.diff(np.concatenate([[0.0], th]))
        e_b = 0.5 * D / ds * (np.dot(dth, dth) + th[0] ** 2)
        return e_b + contact(positions(th), False)[0] - m * th[-1]

    def energy_grad_hess(th, m):
        dth = np.diff(np.concatenate([[0.0], th]))
        e_b = 0.5 * D / ds * (np.dot(dth, dth) + th[0] ** 2)
        g_b = D / ds * (dth - np.concatenate([dth[1:], [0.0]]))
        g_b[0] += D / ds * th[0]
        H_b = D / ds * (2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1))
        H_b[0, 0] += D / ds
        H_b[-1, -1] = D / ds
        x = positions(th)
        e_c, gx, Hx = contact(x)
        # x_j = Σ_{i<j} ds (cos θ_i, sin θ_i): J[(j, c), i] = ds (−sin θ_i, cos θ_i) for i < j.
        J = np.zeros((2 * n + 2, n))
        lower = np.tril(np.ones((n + 1, n)), -1)
        J[0::2] = lower * (-ds * np.sin(th))[None, :]
        J[1::2] = lower * (ds * np.cos(th))[None, :]
        g_c = J.T @ gx.reshape(-1)
        # Second derivative of x_j in θ_i (diagonal): −ds (cos θ_i, sin θ_i) for i < j.
        tail = np.cumsum(gx[::-1], axis=0)[::-1][1:]  # Σ_{j>i} g_j
        diag = -ds * (tail[:, 0] * np.cos(th) + tail[:, 1] * np.sin(th))
        H_c = J.T @ Hx @ J + np.diag(diag)
        e = e_b + e_c - m * th[-1]
        g = g_b + g_c
        g[-1] -= m
        return e, g, H_b + H_c

    for step in range(1, steps + 1):
        m = M * step / steps
        for _ in range(200):
            e, g, H = energy_grad_hess(theta, m)
            if np.max(np.abs(g)) < 1e-8 * M:
                break
            shift = 0.0
            while True:
                try:
                    c = np.linalg.cholesky(H + shift * np.eye(n))
                    break
                except np.linalg.LinAlgError:
                    shift = max(2 * shift, 1e-8 * np.max(np.abs(np.diag(H))))
            p = -np.linalg.solve(c.T, np.linalg.solve(c, g))
            alpha = 1.0
            while alpha > 1e-12:
                e1 = energy_only(theta + alpha * p, m)
                if e1 <= e + 1e-4 * alpha * np.dot(g, p):
                    break
                alpha *= 0.5
            theta = theta + alpha * p
            if np.max(np.abs(alpha * p)) < 1e-13:
                break  # the round-off floor of the stiff penalty, at a gradient near 1e-9 M
        else:
            raise SystemExit(f"elastica: Newton did not converge at load step {step}")
    x = positions(theta)
    return s_node, x, np.concatenate([[0.0], theta])


def read_centreline(out_dir, mesh):
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy

    frame = sorted(glob.glob(os.path.join(out_dir, "frame_*.vtu")))[-1]
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(frame)
    r.Update()
    p = vtk_to_numpy(r.GetOutput().GetPoints().GetData()).astype(float)
    m = vtk.vtkGenericDataObjectReader()
    m.SetFileName(mesh)
    m.Update()
    x0 = vtk_to_numpy(m.GetOutput().GetPoints().GetData()).astype(float)
    stations = np.unique(np.round(x0[:, 0], 9))
    c = np.array([p[np.abs(x0[:, 0] - xs) < 1e-9].mean(axis=0) for xs in stations])
    s = stations - stations[0]
    # Rolling in the x–z plane, relative to the clamped end.
    return s, np.c_[c[:, 0] - c[0, 0], c[:, 2] - c[0, 2]], frame


def tangent_angle(s, x):
    t = np.unwrap(np.arctan2(np.diff(x[:, 1]), np.diff(x[:, 0])))
    mid = 0.5 * (s[1:] + s[:-1])
    return mid, t


def turns(s, x):
    """Mean radius of curvature of the first turn (to θ = 2π) and of the rest (to the tip)."""
    mid, t = tangent_angle(s, x)
    t = t - t[0] if abs(t[0]) > 0.5 else t
    s_turn = np.interp(2 * np.pi, t, mid)
    theta_tip = t[-1] + (t[-1] - t[-2]) / (mid[-1] - mid[-2]) * (s[-1] - mid[-1])
    return s_turn / (2 * np.pi), (s[-1] - s_turn) / (theta_tip - 2 * np.pi), theta_tip


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out_dir")
    ap.add_argument("mesh")
    ap.add_argument("--length", type=float, required=True)
    ap.add_argument("--thickness", type=float, required=True)
    ap.add_argument("--young", type=float, required=True)
    ap.add_argument("--poisson", type=float, required=True)
    ap.add_argument("--moment", type=float, required=True)
    ap.add_argument("--segments", type=int, default=300)
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--json")
    a = ap.parse_args()
    h = a.thickness
    D = a.young * h**3 / (12 * (1 - a.poisson**2))
    s_e, x_e, th_e = solve(a.length, h, D, a.moment, a.segments, a.steps)
    s_m, x_m, frame = read_centreline(a.out_dir, a.mesh)
    r_free = D / a.moment
    e_first, e_second, e_tip = turns(s_e, x_e)
    m_first, m_second, m_tip = turns(s_m, x_m)
    # Positions at equal arc length: the elastica interpolated at the shell's stations.
    xe_at = np.c_[np.interp(s_m, s_e, x_e[:, 0]), np.interp(s_m, s_e, x_e[:, 1])]
    dev = np.max(np.linalg.norm(x_m - xe_at, axis=1))

    def layer_gap(s, x, s_turn):
        """Distances from the tip's turn to the first turn (a polyline), where they overlap."""
        inner = x[s > s_turn + 3 * a.thickness]
        keep = s < s_turn - 3 * a.thickness
        a0, a1 = x[keep][:-1], x[keep][1:]
        e = a1 - a0
        rel = inner[:, None, :] - a0[None, :, :]
        t = np.clip(np.einsum("jik,ik->ji", rel, e) / np.einsum("ij,ij->i", e, e), 0, 1)
        d = np.linalg.norm(rel - t[:, :, None] * e[None, :, :], axis=2).min(axis=1)
        # Only where the tip's turn lies over the first: within 2h of it.
        d = d[d < 2 * a.thickness]
        return float(d.min()), float(np.median(d)), float(d.max())

    out = {
        "frame": frame,
        "free_radius": r_free,
        "elastica": {
            "r0": e_second,
            "r1": e_first,
            "tip_turns": e_tip / (2 * np.pi),
            "gap": layer_gap(s_e, x_e, e_first * 2 * np.pi),
        },
        "shell": {
            "r0": m_second,
            "r1": m_first,
            "tip_turns": m_tip / (2 * np.pi),
            "gap": layer_gap(s_m, x_m, m_first * 2 * np.pi),
        },
        "max_position_deviation_over_r0": dev / e_second,
    }
    out["r0_error"] = m_second / e_second - 1
    out["r1_error"] = m_first / e_first - 1
    out["spiral_r1_minus_r0_over_h"] = {
        "elastica": (e_first - e_second) / h,
        "shell": (m_first - m_second) / h,
    }
    print(json.dumps(out, indent=1))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f)


if __name__ == "__main__":
    main()
