#!/usr/bin/env python3
"""Volumetric 3D finite-element reference for a free bilayer strip that bends because its two
layers swell by different amounts (large deformation). Independent of shellsim's code: only
numpy, scipy and scikit-fem (mesh, triquadratic basis, quadrature) are used.

    bilayer_fem.py [--eps-top E] [--eps-bottom E] [--phi F] [--n N] [--nu NU] [--Eb E]
                   [--h H] [--L L] [--W W] [--width-mode free|plane-strain]
                   [--material neo-hookean|svk] [--nx NX] [--ny NY] [--nz NZ] [--grade G]
                   [--steps S] [--check-tangent | --refine-study | --sweep]

Model
-----
* Reference strip x ∈ [0, L], y ∈ [0, W], z ∈ [0, h]; bottom layer z < (1 − φ)h with Young's
  modulus E_b, top layer with E_t = n E_b, one Poisson ratio ν.
* Multiplicative split F = F_e G with isotropic growth G = s I, s = 1 + ε_layer (Rodriguez,
  Hoger & McCulloch 1994, J. Biomech. 27:455). The energy per reference volume is
  Ψ(F) = det(G) W(F G⁻¹) = s³ W(F/s): the grown volume carries the elastic energy.
* Elastic law: compressible neo-Hookean (Bonet & Wood, Nonlinear Continuum Mechanics for
  Finite Element Analysis, 2nd ed. 2008, ch. 6),
      W = μ/2 (I₁ − 3 − 2 ln J) + λ/2 (ln J)²,  μ = E/(2(1+ν)),  λ = Eν/((1+ν)(1−2ν)),
  or St Venant–Kirchhoff (`--material svk`, same chapter),
      W = λ/2 (tr E)² + μ E:E,  E = (F_eᵀF_e − I)/2.
* Symmetry: a quarter is meshed, x ∈ [L/2, L] and y ∈ [W/2, W], with u_x = 0 on x = L/2 and
  u_y = 0 on y = W/2. `free` width mode leaves the side face y = W free (a narrow 3D strip);
  `plane-strain` also sets u_y = 0 on y = W. One u_z = 0 at the node x = L/2, y = W/2, z nearest
  h/2 removes the last rigid motion. Nothing else is constrained.
* Discretisation: 27-node triquadratic hexahedra (scikit-fem ElementHex2) on a structured
  tensor mesh (MeshHex.init_tensor), 3×3×3 Gauss points; the layer interface is a mesh plane.
  nx elements along the meshed half length, ny across the meshed half width, nz through the
  thickness (shared between the layers in proportion to their thickness). `--grade` shrinks the
  elements toward the interface and toward the free side face, where the free edge of the
  interface concentrates stress and slows convergence (default 1 in free width, 0 in plane
  strain, whose solution is smooth in each layer).
* Solution: full Newton with the consistent tangent (checked by `--check-tangent` against
  central differences), load continuation along a straight path in (ε_bottom, ε_top) (one step
  per 0.05 of eigenstrain by default), predictor by cubic Hermite extrapolation of the last two
  converged states and their tangents du/dλ = −K⁻¹ ∂R/∂λ (Euler on the first step), a
  backtracking line search accepting an Armijo decrease of the energy or of ‖R‖², and step
  halving when Newton fails. Converged when ‖R‖ ≤ 1e-10 ‖R₀‖ (R₀: the residual at the step's
  new growth and the previous displacement) or ‖R‖ ≤ 1e-13 of a round-off force scale.
* Measurement (middle half |x − L/2| ≤ L/4, centre line y = W/2): the deformed node lines at
  the reference heights z = 0, (1 − φ)h, h/2 and h (mirrored about x = L/2; a height between
  node planes is evaluated exactly by the Q2 field's quadratic interpolation in z) are fitted by
  a circle: Kåsa's algebraic fit (Kåsa 1976, IEEE Trans. Instrum. Meas. 25:8) refined by a
  Gauss–Newton fit of the geometric distances. Curvature is positive when the strip bends
  toward +z (the circle's centre above the strip). kappa_mid = 2/(R_bottom + R_top); the
  deformed thickness is the distance between the bottom and top points at x = L/2, y = W/2.
* Reference: Timoshenko (1925), "Analysis of bi-metal thermostats", J. Opt. Soc. Am. 11:233,
      1/ρ = 6 Δε (1 + m)² / (h [3(1 + m)² + (1 + m n)(m² + 1/(m n))]),
  m = a₁/a₂ (thickness ratio), n = E₁/E₂ (modulus ratio) of the same two layers; for plane
  strain an isotropic eigenstrain acts as (1 + ν)Δε (the E/(1 − ν²) factors cancel).

* Plane strain also gets an exact large-deformation reference: the uniform bending state far
  from the ends reduced to a 1D problem through the thickness (uniform_bending_plane_strain).

Output and modes (one JSON object per line on stdout)
------------------------------------------------------
* default: one case: inputs, dofs, wall and CPU time, Newton iterations, load steps, the four
  lines' R, signed curvature, fit rms and subtended angle, kappa_mid, the deformed thickness,
  Timoshenko's κ and the ratio (and, in plane strain, the 1D uniform-bending solution).
* --sweep: ε_top = 0.05, 0.10, 0.20, 0.35, 0.50 with ε_bottom = 0, one line each.
* --refine-study: the case on coarser and finer meshes along x and across the section, then
  a summary line with the observed orders, the Richardson limit of kappa_mid and the
  estimated relative error of the given mesh.
* --check-tangent: tangent, gradient and ∂R/∂λ against central differences on a small mesh.
"""

import os

# One BLAS thread: the machine is shared and the timings quoted are for one core.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from dataclasses import asdict, dataclass, replace  # noqa: E402

import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402
import scipy.sparse.linalg as spla  # noqa: E402
from skfem import Basis, ElementHex2, MeshHex  # noqa: E402

I3 = np.eye(3)


class NonPhysical(Exception):
    """A state with det F_e ≤ 0 (or not finite) somewhere: the step must be shortened."""


# ----------------------------------------------------------------------------------------------
# Parameters
# ----------------------------------------------------------------------------------------------

@dataclass
class Case:
    h: float = 1.0
    L: float = 20.0
    W: float = 1.0
    phi: float = 0.5          # top layer's share of the thickness
    n: float = 1.0            # E_top / E_bottom
    nu: float = 0.3
    Eb: float = 1.0
    eps_top: float = 0.1
    eps_bottom: float = 0.0
    material: str = "neo-hookean"
    width_mode: str = "free"
    nx: int = 40              # elements along x over the meshed half length
    ny: int = 2               # elements across the meshed half width
    nz: int = 8               # elements through the thickness (both layers)
    grade: float = 1.0        # mesh grading toward the interface and the free side face


# ----------------------------------------------------------------------------------------------
# Materials: W, P = ∂W/∂F and A = ∂P/∂F for arrays of F of shape (..., 3, 3); mu, lam broadcast.
# ----------------------------------------------------------------------------------------------

def neo_hookean(F, mu, lam, tangent=True):
    """Compressible neo-Hookean (Bonet & Wood 2008, ch. 6):
    W = μ/2 (tr FᵀF − 3) − μ ln J + λ/2 (ln J)²,
    P = μ (F − F⁻ᵀ) + λ ln J F⁻ᵀ,
    A_iJkL = μ δ_ik δ_JL + (μ − λ ln J) F⁻¹_Li F⁻¹_Jk + λ F⁻¹_Ji F⁻¹_Lk
    (the last from ∂F⁻¹_Ji/∂F_kL = −F⁻¹_Jk F⁻¹_Li and ∂ ln J/∂F_kL = F⁻¹_Lk)."""
    J = np.linalg.det(F)
    if not np.all(np.isfinite(J)) or np.any(J <= 0.0):
        raise NonPhysical
    Finv = np.linalg.inv(F)
    FinvT = np.swapaxes(Finv, -1, -2)
    lnJ = np.log(J)
    m2, l2 = mu[..., None, None], lam[..., None, None]
    W = 0.5 * mu * (np.einsum("...iJ,...iJ->...", F, F) - 3.0 - 2.0 * lnJ) + 0.5 * lam * lnJ**2
    P = m2 * (F - FinvT) + l2 * lnJ[..., None, None] * FinvT
    if not tangent:
        return W, P, None
    m4 = mu[..., None, None, None, None]
    l4 = lam[..., None, None, None, None]
    A = (m4 * np.einsum("ik,JL->iJkL", I3, I3)
         + (m4 - l4 * lnJ[..., None, None, None, None])
         * np.einsum("...Li,...Jk->...iJkL", Finv, Finv)
         + l4 * np.einsum("...Ji,...Lk->...iJkL", Finv, Finv))
    return W, P, A


def st_venant_kirchhoff(F, mu, lam, tangent=True):
    """St Venant–Kirchhoff (Bonet & Wood 2008, ch. 6): E = (FᵀF − I)/2,
    W = λ/2 (tr E)² + μ E:E, S = λ tr E I + 2μ E, P = F S,
    A_iJkL = δ_ik S_JL + λ F_iJ F_kL + μ (F_iL F_kJ + (F Fᵀ)_ik δ_JL)
    (from ∂E_MN/∂F_kL = (δ_ML F_kN + F_kM δ_NL)/2)."""
    if not np.all(np.isfinite(F)):
        raise NonPhysical
    E = 0.5 * (np.einsum("...kI,...kJ->...IJ", F, F) - I3)
    trE = np.einsum("...II->...", E)
    m2, l2 = mu[..., None, None], lam[..., None, None]
    W = 0.5 * lam * trE**2 + mu * np.einsum("...IJ,...IJ->...", E, E)
    S = l2 * trE[..., None, None] * I3 + 2.0 * m2 * E
    P = F @ S
    if not tangent:
        return W, P, None
    m4 = mu[..., None, None, None, None]
    l4 = lam[..., None, None, None, None]
    FFt = F @ np.swapaxes(F, -1, -2)
    A = (np.einsum("ik,...JL->...iJkL", I3, S)
         + l4 * np.einsum("...iJ,...kL->...iJkL", F, F)
         + m4 * (np.einsum("...iL,...kJ->...iJkL", F, F)
                 + np.einsum("...ik,JL->...iJkL", FFt, I3)))
    return W, P, A


MATERIALS = {"neo-hookean": neo_hookean, "svk": st_venant_kirchhoff}


# ----------------------------------------------------------------------------------------------
# Closed forms
# ----------------------------------------------------------------------------------------------

def timoshenko_kappa(c: Case):
    """Signed small-strain curvature of the bilayer (Timoshenko 1925, J. Opt. Soc. Am. 11:233):
    1/ρ = 6 Δε (1+m)² / (h [3(1+m)² + (1+mn)(m² + 1/(mn))]) with m = t_top/t_bottom and
    n = E_top/E_bottom (both ratios taken top over bottom; the formula is invariant under
    swapping the layers, m → 1/m, n → 1/n). The layer that swells more is on the convex side,
    so a larger top eigenstrain bends toward −z (negative here). Plane strain: an isotropic
    eigenstrain ε gives the in-plane free strain (1 + ν)ε, and the plane-strain moduli
    E/(1 − ν²) keep the ratio n."""
    m = c.phi / (1.0 - c.phi)
    n = c.n
    d_eps = c.eps_top - c.eps_bottom
    if c.width_mode == "plane-strain":
        d_eps *= 1.0 + c.nu
    k = 6.0 * d_eps * (1 + m) ** 2 / (c.h * (3 * (1 + m) ** 2 + (1 + m * n) * (m**2 + 1 / (m * n))))
    return -k


def uniform_bending_plane_strain(c: Case, ne_layer=32):
    """The exact large-deformation state of a long plane-strain bilayer far from its ends,
    reduced to one dimension (the flexure of a block, Rivlin 1949, "Large elastic deformations
    of isotropic materials V", Proc. R. Soc. Lond. A 195:463): the reference point (X, Y, Z) goes to radius ρ(Z) and angle κX about a
    fixed axis along y, so F has the principal stretches λ₁ = κρ (along the strip), λ₂ = 1
    (plane strain) and λ₃ = |ρ'(Z)| (through the thickness). With ρ = (1 + e₀)/κ + v(Z),
    v(0) = 0, the unknowns e₀, κ and v(Z) (quadratic elements, ne_layer per layer) stay O(1)
    down to κ → 0: λ₁ = 1 + e₀ + κ v, λ₃ = d v' (d = +1 when the circle's centre is below the
    strip, i.e. the top layer swells more). The energy per unit reference length and width,
    Π = ∫₀ʰ s³ W(λ₁/s, 1/s, λ₃/s) dZ, is minimised by Newton's method (exact gradient and
    Hessian from the same material functions at diagonal F, where P_ii = ∂W/∂λᵢ and
    A_iikk = ∂²W/∂λᵢ∂λₖ) with continuation in the growth. Returns the signed kappa_mid =
    2/(ρ(0) + ρ(h)) and the deformed thickness |ρ(h) − ρ(0)|, the 3D measurement's analogues
    (None without mismatch)."""
    if c.eps_top == c.eps_bottom:
        return None                                               # no mismatch: flat
    h, zi = c.h, (1.0 - c.phi) * c.h
    zb = np.concatenate([np.linspace(0.0, zi, ne_layer + 1), np.linspace(zi, h, ne_layer + 1)[1:]])
    ne, le = len(zb) - 1, np.diff(zb)
    nn = 2 * ne + 1
    gp, gw = np.polynomial.legendre.leggauss(4)
    xi, wq = 0.5 * (gp + 1.0), 0.5 * gw
    # quadratic Lagrange shape functions on [0, 1] with nodes 0, 1/2, 1, and their derivatives
    N1 = np.stack([2 * (xi - 0.5) * (xi - 1), -4 * xi * (xi - 1), 2 * xi * (xi - 0.5)], axis=1)
    dN1 = np.stack([4 * xi - 3, 4 - 8 * xi, 4 * xi - 1], axis=1)
    nq = ne * len(xi)
    Nq, dNq = np.zeros((nq, nn)), np.zeros((nq, nn))
    for e in range(ne):
        rows = slice(e * len(xi), (e + 1) * len(xi))
        Nq[rows, 2 * e:2 * e + 3] = N1
        dNq[rows, 2 * e:2 * e + 3] = dN1 / le[e]
    w = np.repeat(le, len(xi)) * np.tile(wq, ne)
    top = np.repeat(zb[:-1] + 0.5 * le > zi, len(xi))
    E = np.where(top, c.n * c.Eb, c.Eb)
    mu, lam = E / (2.0 * (1.0 + c.nu)), E * c.nu / ((1.0 + c.nu) * (1.0 - 2.0 * c.nu))
    material = MATERIALS[c.material]
    d = 1.0 if c.eps_top >= c.eps_bottom else -1.0
    znode = with_midpoints(zb)

    def evaluate(q, eps_bottom, eps_top, tangent):
        v, kap, e0 = q[:nn], q[nn], q[nn + 1]
        s = 1.0 + np.where(top, eps_top, eps_bottom)
        r = Nq @ v
        l1, l3 = 1.0 + e0 + kap * r, d * (dNq @ v)
        F = np.zeros((nq, 3, 3))
        F[:, 0, 0], F[:, 1, 1], F[:, 2, 2] = l1 / s, 1.0 / s, l3 / s
        W, P, A = material(F, mu, lam, tangent)
        # Ψ(λ) = s³ W(λ/s): ∂Ψ/∂λᵢ = s² W_i, ∂²Ψ/∂λᵢ∂λₖ = s W_ik
        p1, p3 = w * s**2 * P[:, 0, 0], w * s**2 * P[:, 2, 2]
        D1 = np.column_stack([kap * Nq, r, np.ones(nq)])          # ∂λ₁/∂q
        D3 = np.column_stack([d * dNq, np.zeros(nq), np.zeros(nq)])  # ∂λ₃/∂q
        g = D1.T @ p1 + D3.T @ p3
        if not tangent:
            return float(np.sum(w * s**3 * W)), g, None
        a11, a13, a33 = (w * s * A[:, i, i, k, k] for i, k in ((0, 0), (0, 2), (2, 2)))
        H = (D1.T @ (a11[:, None] * D1) + D1.T @ (a13[:, None] * D3) + D3.T @ (a13[:, None] * D1)
             + D3.T @ (a33[:, None] * D3))
        H[:nn, nn] += Nq.T @ p1                                   # ∂²λ₁/∂v∂κ = N
        H[nn, :nn] += Nq.T @ p1
        return float(np.sum(w * s**3 * W)), g, H

    nsteps = auto_steps(max(abs(c.eps_top), abs(c.eps_bottom), abs(c.eps_top - c.eps_bottom)))
    k1 = abs(timoshenko_kappa(replace(c, eps_top=c.eps_top / nsteps,
                                      eps_bottom=c.eps_bottom / nsteps)))
    q = np.concatenate([d * znode, [k1, 0.5 * (c.eps_top + c.eps_bottom) / nsteps]])
    act = np.arange(1, nn + 2)                                    # v(0) = 0 is pinned
    for k in range(1, nsteps + 1):
        eb, et = c.eps_bottom * k / nsteps, c.eps_top * k / nsteps
        e, g, H = evaluate(q, eb, et, True)
        g0 = gprev = np.linalg.norm(g[act])
        for _ in range(60):
            sc = 1.0 / np.sqrt(np.abs(np.diag(H)[act]))          # Jacobi scaling of the solve
            step = np.zeros_like(q)
            step[act] = -sc * np.linalg.solve(H[np.ix_(act, act)] * np.outer(sc, sc), g[act] * sc)
            alpha = 1.0
            while alpha > 1e-8:                                   # Armijo on Π or on ‖g‖
                try:
                    e2, g2, _ = evaluate(q + alpha * step, eb, et, False)
                    if (e2 <= e + 1e-4 * alpha * (g @ step)
                            or np.linalg.norm(g2[act]) < np.linalg.norm(g[act])):
                        break
                except NonPhysical:
                    pass
                alpha *= 0.5
            q = q + alpha * step
            e, g, H = evaluate(q, eb, et, True)
            gn = np.linalg.norm(g[act])
            # converged: 1e-12 of the step's first gradient, or stalled at round-off (a full
            # Newton step near the solution that no longer halves the gradient)
            if gn <= 1e-12 * g0 or (alpha == 1.0 and gn <= 1e-3 * g0 and gn > 0.5 * gprev):
                break
            gprev = gn
        else:
            raise RuntimeError("uniform-bending solution did not converge")
    v, kap, e0 = q[:nn], q[nn], q[nn + 1]
    rho_b, rho_t = (1.0 + e0) / kap + v[0], (1.0 + e0) / kap + v[-1]
    return {"kappa_mid": -d * 2.0 * kap / (2.0 * (1.0 + e0) + kap * (v[0] + v[-1])),
            "R_bottom": rho_b, "R_top": rho_t, "thickness": abs(v[-1] - v[0])}


# ----------------------------------------------------------------------------------------------
# Circle fit
# ----------------------------------------------------------------------------------------------

def fit_circle(x, z):
    """Least-squares circle through points (x, z): Kåsa's algebraic fit (minimise
    Σ (x² + z² + D x + E z + F)², linear in D, E, F), then Gauss–Newton on the geometric
    residuals r_i = |p_i − c| − R (Jacobian ∂r/∂c = −(p_i − c)/|p_i − c|, ∂r/∂R = −1).
    Coordinates are centred first for conditioning. Returns (xc, zc, R, rms)."""
    x0, z0 = x.mean(), z.mean()
    X, Z = x - x0, z - z0
    M = np.column_stack([X, Z, np.ones_like(X)])
    D, E, F = np.linalg.lstsq(M, -(X**2 + Z**2), rcond=None)[0]
    a, b = -D / 2.0, -E / 2.0
    R = math.sqrt(max(a * a + b * b - F, 0.0))
    for _ in range(50):
        dxp, dzp = X - a, Z - b
        d = np.hypot(dxp, dzp)
        r = d - R
        Jm = np.column_stack([-dxp / d, -dzp / d, -np.ones_like(d)])
        step = np.linalg.lstsq(Jm, -r, rcond=None)[0]
        a, b, R = a + step[0], b + step[1], R + step[2]
        if np.max(np.abs(step)) <= 1e-14 * max(R, 1.0):
            break
    rms = float(np.sqrt(np.mean((np.hypot(X - a, Z - b) - R) ** 2)))
    return a + x0, b + z0, abs(R), rms


# ----------------------------------------------------------------------------------------------
# One-dimensional quadratic Lagrange interpolation on a piecewise-quadratic grid
# ----------------------------------------------------------------------------------------------

def quad_interp_matrix(grid, pts):
    """Matrix M with M @ values(grid) = the piecewise-quadratic interpolant at pts. `grid` holds
    element vertices at even indices and midpoints at odd ones (a Q2 node line); the triquadratic
    Hex2 field restricted to a node line is exactly this interpolant."""
    ne = (len(grid) - 1) // 2
    M = np.zeros((len(pts), len(grid)))
    for r, p in enumerate(pts):
        k = min(max(np.searchsorted(grid[0::2], p, side="right") - 1, 0), ne - 1)
        z0, z1, z2 = grid[2 * k], grid[2 * k + 1], grid[2 * k + 2]
        # Lagrange basis on three nodes
        M[r, 2 * k] = (p - z1) * (p - z2) / ((z0 - z1) * (z0 - z2))
        M[r, 2 * k + 1] = (p - z0) * (p - z2) / ((z1 - z0) * (z1 - z2))
        M[r, 2 * k + 2] = (p - z0) * (p - z1) / ((z2 - z0) * (z2 - z1))
    return M


def graded_unit(n, grade, at_end):
    """n + 1 points on [0, 1]: (1 − grade) ξ + grade sin(πξ/2) with ξ uniform, which for
    grade = 1 shrinks the elements toward 1 (the last is π²/(8n²) long instead of 1/n); mirrored
    toward 0 when at_end is False."""
    xi = np.linspace(0.0, 1.0, n + 1)
    if at_end:
        return (1.0 - grade) * xi + grade * np.sin(0.5 * np.pi * xi)
    return (1.0 - grade) * xi + grade * (1.0 - np.cos(0.5 * np.pi * xi))


def with_midpoints(v):
    """The node coordinates of a Q2 line: the vertices v with their midpoints in between."""
    out = np.empty(2 * len(v) - 1)
    out[0::2] = v
    out[1::2] = 0.5 * (v[:-1] + v[1:])
    return out


# ----------------------------------------------------------------------------------------------
# The discrete model
# ----------------------------------------------------------------------------------------------

class Strip:
    """A quarter of the strip, x ∈ [L/2, L], y ∈ [W/2, W], meshed with triquadratic hexahedra."""

    CHUNK = 96  # elements per batch in the stiffness computation

    def __init__(self, c: Case):
        if c.nz < 2:
            raise ValueError("nz must be at least 2 (one element per layer)")
        self.c = c
        h, L, W = c.h, c.L, c.W
        self.z_int = (1.0 - c.phi) * h
        nzb = min(max(int(round(c.nz * (1.0 - c.phi))), 1), c.nz - 1)
        # quarter of the strip: x ∈ [L/2, L], y ∈ [W/2, W]; y graded toward the free side face
        # y = W and z toward the interface from both sides (`grade`, see graded_unit)
        xs = np.linspace(0.5 * L, L, c.nx + 1)
        ys = 0.5 * W * (1.0 + graded_unit(c.ny, c.grade, at_end=True))
        zs = np.concatenate([self.z_int * graded_unit(nzb, c.grade, at_end=True),
                             self.z_int + (h - self.z_int)
                             * graded_unit(c.nz - nzb, c.grade, at_end=False)[1:]])
        self.mesh = MeshHex.init_tensor(xs, ys, zs)
        self.basis = Basis(self.mesh, ElementHex2(), intorder=4)  # 3×3×3 Gauss points
        b = self.basis
        self.N = b.N
        self.ndof = 3 * self.N
        self.nel = self.mesh.t.shape[1]
        self.X = b.doflocs.T.copy()                              # (N, 3) reference positions
        # ∂N_a/∂X_J at the quadrature points, shape (E, Q, 27, 3); dV weights (E, Q)
        self.dN = np.ascontiguousarray(
            np.stack([b.basis[a][0].grad for a in range(b.Nbfun)]).transpose(2, 3, 0, 1))
        self.dx = np.ascontiguousarray(b.dx)
        self.nq = self.dx.shape[1]
        # vector dof numbering: 3 × (scalar dof) + component
        self.ed3 = (3 * b.element_dofs.T[:, :, None] + np.arange(3)).reshape(self.nel, -1)

        # layers: element centroids below or above the interface
        zc = self.mesh.p[2, self.mesh.t].mean(axis=0)
        self.top = zc > self.z_int
        E = np.where(self.top, c.n * c.Eb, c.Eb)
        self.mu = E / (2.0 * (1.0 + c.nu))                                     # shear modulus
        self.lam = E * c.nu / ((1.0 + c.nu) * (1.0 - 2.0 * c.nu))              # Lamé λ
        self.material = MATERIALS[c.material]

        # structured node grid (the Hex2 nodes lie on the element grid with midpoints)
        self.xg, self.yg, self.zg = with_midpoints(xs), with_midpoints(ys), with_midpoints(zs)
        idx = []
        for k, axis in enumerate((self.xg, self.yg, self.zg)):
            i = np.clip(np.searchsorted(axis, self.X[:, k] - 1e-9 * h), 0, len(axis) - 1)
            if np.max(np.abs(axis[i] - self.X[:, k])) > 1e-9 * h:
                raise RuntimeError("Hex2 nodes do not match the tensor grid")
            idx.append(i)
        self.grid = np.full((len(self.xg), len(self.yg), len(self.zg)), -1)
        self.grid[idx[0], idx[1], idx[2]] = np.arange(self.N)
        assert np.all(self.grid >= 0)

        # constraints (see the module docstring)
        tol = 1e-9 * h
        fixed = [3 * np.flatnonzero(np.abs(self.X[:, 0] - 0.5 * L) < tol)]          # u_x, x = L/2
        fixed.append(3 * np.flatnonzero(np.abs(self.X[:, 1] - 0.5 * W) < tol) + 1)  # u_y, y = W/2
        if c.width_mode == "plane-strain":
            fixed.append(3 * np.flatnonzero(np.abs(self.X[:, 1] - W) < tol) + 1)    # u_y, y = W
        elif c.width_mode != "free":
            raise ValueError(c.width_mode)
        self.iyc = 0                                                   # the centre line y = W/2
        izc = int(np.argmin(np.abs(self.zg - 0.5 * h)))
        fixed.append(np.array([3 * self.grid[0, self.iyc, izc] + 2]))
        self.fixed = np.unique(np.concatenate(fixed))
        self.free = np.setdiff1d(np.arange(self.ndof), self.fixed)
        self.nfree = len(self.free)
        self._build_pattern()
        self._force_scale()

    # ------------------------------------------------------------------ sparsity, scales
    def _build_pattern(self):
        """Reduced (free × free) CSR pattern and the map from element-matrix entries to it."""
        g2f = np.full(self.ndof, -1)
        g2f[self.free] = np.arange(self.nfree)
        fe = g2f[self.ed3]                                          # (E, 81)
        rows = np.broadcast_to(fe[:, :, None], (self.nel, 81, 81)).ravel()
        cols = np.broadcast_to(fe[:, None, :], (self.nel, 81, 81)).ravel()
        self.k_mask = (rows >= 0) & (cols >= 0)
        key = rows[self.k_mask].astype(np.int64) * self.nfree + cols[self.k_mask]
        ukey, self.k_inv = np.unique(key, return_inverse=True)
        self.k_nnz = len(ukey)
        r, self.k_indices = np.divmod(ukey, self.nfree)
        self.k_indptr = np.concatenate([[0], np.cumsum(np.bincount(r, minlength=self.nfree))])

    def _force_scale(self):
        """Round-off force scale: ‖Σ_e Σ_q (2μ+λ) |∂N_a/∂X| dV‖ over all dofs. A residual below
        1e-13 of it is at the rounding level of the stresses' assembly."""
        w = ((2 * self.mu + self.lam)[:, None, None]
             * np.abs(self.dN).sum(axis=3).transpose(0, 2, 1)
             * self.dx[:, None, :]).sum(axis=2)                     # (E, 27)
        f = np.bincount(self.ed3.ravel(), weights=np.repeat(w, 3, axis=1).ravel(),
                        minlength=self.ndof)
        self.fscale = float(np.linalg.norm(f[self.free]))

    # ------------------------------------------------------------------ kinematics, stress
    def growth(self, eps_bottom, eps_top):
        """Per-element growth stretch s = 1 + ε_layer."""
        return 1.0 + np.where(self.top, eps_top, eps_bottom)

    def F(self, u):
        """Deformation gradient F_iJ = δ_iJ + Σ_a u_ai ∂N_a/∂X_J, shape (E, Q, 3, 3)."""
        ue = u[self.ed3].reshape(self.nel, -1, 3)
        return I3 + np.einsum("eai,eqaJ->eqiJ", ue, self.dN, optimize=True)

    def stress(self, u, s, tangent):
        """Ψ = s³ W(F/s), P = ∂Ψ/∂F = s² P_e(F/s), A = ∂P/∂F = s A_e(F/s) (chain rule of the
        growth split Ψ(F) = det G W(F G⁻¹) with G = s I). Also returns F, P_e, A_e."""
        F = self.F(u)
        s2 = s[:, None, None, None]
        Fe = F / s2
        mu = np.broadcast_to(self.mu[:, None], self.dx.shape)
        lam = np.broadcast_to(self.lam[:, None], self.dx.shape)
        W, Pe, Ae = self.material(Fe, mu, lam, tangent)
        psi = s[:, None] ** 3 * W
        P = s2**2 * Pe
        A = None if Ae is None else s[:, None, None, None, None, None] * Ae
        return psi, P, A, F, Pe, Ae

    def assemble_vector(self, P):
        """R_ai = Σ_e Σ_q P_iJ ∂N_a/∂X_J dV (the weak form's internal force)."""
        Re = np.einsum("eqiJ,eqaJ->eai", P * self.dx[:, :, None, None], self.dN, optimize=True)
        return np.bincount(self.ed3.ravel(), weights=Re.ravel(), minlength=self.ndof)

    def assemble_matrix(self, A):
        """K_(ai)(bk) = Σ_e Σ_q ∂N_a/∂X_J A_iJkL ∂N_b/∂X_L dV, restricted to the free dofs.
        Returns a CSR matrix."""
        E, Q = self.nel, self.nq
        Ke = np.empty((E, 81 * 81))
        for c0 in range(0, E, self.CHUNK):
            c1 = min(c0 + self.CHUNK, E)
            ne = c1 - c0
            dN = self.dN[c0:c1]                                       # (e, q, a, J)
            Aw = A[c0:c1] * self.dx[c0:c1, :, None, None, None, None]  # (e, q, i, J, k, L)
            # T[e,q,a,(i,k,L)] = Σ_J dN[e,q,a,J] Aw[e,q,i,J,k,L]
            T = dN @ Aw.transpose(0, 1, 3, 2, 4, 5).reshape(ne, Q, 3, 27)
            T = T.reshape(ne, Q, 27, 3, 3, 3).transpose(0, 2, 3, 4, 1, 5).reshape(ne, 243, 3 * Q)
            B = dN.transpose(0, 1, 3, 2).reshape(ne, 3 * Q, 27)       # [(q, L), b]
            Kc = (T @ B).reshape(ne, 27, 3, 3, 27)                    # [a, i, k, b]
            Ke[c0:c1] = Kc.transpose(0, 1, 2, 4, 3).reshape(ne, -1)
        data = np.bincount(self.k_inv, weights=Ke.ravel()[self.k_mask], minlength=self.k_nnz)
        return sp.csr_matrix((data, self.k_indices, self.k_indptr), shape=(self.nfree,) * 2)

    # ------------------------------------------------------------------ public evaluations
    def energy(self, u, s):
        psi = self.stress(u, s, False)[0]
        return float(np.sum(psi * self.dx))

    def energy_residual(self, u, s):
        psi, P = self.stress(u, s, False)[:2]
        return float(np.sum(psi * self.dx)), self.assemble_vector(P)[self.free]

    def residual(self, u, s):
        return self.assemble_vector(self.stress(u, s, False)[1])[self.free]

    def residual_tangent(self, u, s):
        _, P, A, _, _, _ = self.stress(u, s, True)
        return self.assemble_vector(P)[self.free], self.assemble_matrix(A)

    def dresidual_ds(self, u, s, ds):
        """∂R/∂λ for a load path s(λ) with ds = ∂s/∂λ per element, from
        ∂P/∂s = 2 s P_e(F/s) − A_e(F/s) : F (differentiate P = s² P_e(F/s))."""
        _, _, _, F, Pe, Ae = self.stress(u, s, True)
        dP = 2.0 * s[:, None, None, None] * Pe - np.einsum("eqiJkL,eqkL->eqiJ", Ae, F)
        return self.assemble_vector(dP * ds[:, None, None, None])[self.free]

    # ------------------------------------------------------------------ measurement
    def node_line(self, u, z_ref, ix):
        """Deformed positions (len(ix), 3) of the line y = W/2, z = z_ref at grid columns ix
        (exact evaluation of the Q2 field: quadratic Lagrange interpolation in z)."""
        pos = self.X + u.reshape(-1, 3)
        col = pos[self.grid[ix, self.iyc, :]]                         # (nx, nzg, 3)
        M = quad_interp_matrix(self.zg, [z_ref])[0]
        return np.einsum("k,xkc->xc", M, col)

    def measure(self, u):
        c = self.c
        ix = np.flatnonzero(self.xg <= 0.75 * c.L + 1e-9 * c.h)       # middle half, one side
        levels = {"bottom": 0.0, "interface": self.z_int, "mid": 0.5 * c.h, "top": c.h}
        out = {}
        for name, z in levels.items():
            p = self.node_line(u, z, ix)
            # mirror about the symmetry plane x = L/2 (the point on it appears once)
            x = np.concatenate([c.L - p[:0:-1, 0], p[:, 0]])
            zz = np.concatenate([p[:0:-1, 2], p[:, 2]])
            xc, zc, R, rms = fit_circle(x, zz)
            sign = 1.0 if zc > p[0, 2] else -1.0
            # angle the fitted middle half subtends about the centre (may exceed 360°)
            phi = np.unwrap(np.arctan2(zz - zc, x - xc))
            out[name] = {"z_ref": z, "R": R, "kappa": sign / R, "fit_rms": rms,
                         "centre_xz": [xc, zc],
                         "arc_deg": float(np.degrees(abs(phi[-1] - phi[0])))}
        sign_b = np.sign(out["bottom"]["kappa"])
        sign_t = np.sign(out["top"]["kappa"])
        if sign_b != sign_t:
            raise RuntimeError("top and bottom lines bend opposite ways")
        kmid = sign_b * 2.0 / (out["bottom"]["R"] + out["top"]["R"])
        pb = self.node_line(u, 0.0, np.array([0]))[0]
        pt = self.node_line(u, c.h, np.array([0]))[0]
        return out, float(kmid), float(np.linalg.norm(pt - pb))

    def prolong(self, other, u_other):
        """Interpolate another Strip's displacement (same geometry) onto this mesh's nodes: the
        triquadratic field is a tensor product of 1D quadratics, so interpolate along x, y, z."""
        U = u_other.reshape(-1, 3)[other.grid]                       # (nxg, nyg, nzg, 3)
        Mx = quad_interp_matrix(other.xg, self.xg)
        My = quad_interp_matrix(other.yg, self.yg)
        Mz = quad_interp_matrix(other.zg, self.zg)
        V = np.einsum("Xx,Yy,Zz,xyzc->XYZc", Mx, My, Mz, U, optimize=True)
        u = np.zeros(self.ndof)
        u.reshape(-1, 3)[self.grid.ravel()] = V.reshape(-1, 3)
        u[self.fixed] = 0.0
        return u


# ----------------------------------------------------------------------------------------------
# Newton's method and load continuation
# ----------------------------------------------------------------------------------------------

class Solver:
    RTOL = 1e-10
    ATOL_REL = 1e-13   # of the round-off force scale
    MAXIT = 25

    def __init__(self, model: Strip):
        self.m = model
        self.iterations = 0
        self.cuts = 0
        self.steps = 0
        self.lu = None
        self.last_rel = None

    def factor(self, K):
        """LU of K. K is symmetric, so the CSR arrays read as CSC are Kᵀ = K up to rounding;
        `solve` then uses trans='T' to solve with K exactly as assembled."""
        Kt = sp.csc_matrix((K.data, K.indices, K.indptr), shape=K.shape)
        self.lu = spla.splu(Kt, permc_spec="MMD_AT_PLUS_A",
                            options={"SymmetricMode": True}, diag_pivot_thresh=0.1)

    def solve(self, b):
        return self.lu.solve(b, trans="T")

    def newton(self, u, s, r0):
        """Newton iterations at fixed growth s from the full displacement vector u (not
        modified); r0 is the reference for the relative tolerance. Returns (u, iterations) or
        raises RuntimeError on failure."""
        m = self.m
        u = u.copy()
        E, R = m.energy_residual(u, s)
        atol = self.ATOL_REL * m.fscale
        tol = max(self.RTOL * r0, atol)
        rn = np.linalg.norm(R)
        for it in range(self.MAXIT + 1):
            if rn <= tol:
                self.last_rel = rn / r0 if r0 > 0 else 0.0
                return u, it
            if it == self.MAXIT:
                break
            R, K = m.residual_tangent(u, s)
            self.factor(K)
            du = -self.solve(R)
            slope = R @ du
            self.iterations += 1
            # Backtracking: accept α when the energy Π or the merit ‖R‖² meets an Armijo condition
            # (dΠ/dα = R·du, d‖R‖²/dα = −2‖R‖² at α = 0). The energy is the better guide far from
            # equilibrium (a full step may raise ‖R‖ through stiff membrane terms while lowering
            # Π), ‖R‖ near convergence, where differences of Π fall below round-off.
            alpha = 1.0
            for _ in range(12):
                trial = u.copy()
                trial[m.free] += alpha * du
                try:
                    Et, Rt = m.energy_residual(trial, s)
                    rt = np.linalg.norm(Rt)
                except NonPhysical:
                    Et, rt = np.inf, np.inf
                ok_r = rt**2 <= (1.0 - 1e-4 * alpha) * rn**2 or rt <= tol
                ok_e = slope < 0 and Et <= E + 1e-4 * alpha * slope
                if ok_r or ok_e:
                    break
                alpha *= 0.5
            else:
                # no decrease: at the rounding floor (tiny step) count as converged
                if np.max(np.abs(du)) <= 1e-12 * m.c.h and np.isfinite(rt):
                    self.last_rel = rt / r0 if r0 > 0 else 0.0
                    return trial, it + 1
                raise RuntimeError("line search failed")
            u, R, rn, E = trial, Rt, rt, Et
        raise RuntimeError("Newton did not converge")

    def continuation(self, u, eps_from, eps_to, nsteps, max_halvings=8):
        """Follow growth from eps_from = (ε_bottom, ε_top) to eps_to along a straight path
        λ ∈ [0, 1] in `nsteps` equal increments (an increment is halved while Newton fails). The
        tangent du/dλ = −K⁻¹ ∂R/∂λ at each converged state uses the last factorization; the
        predictor is Euler on the first step, then a cubic Hermite extrapolation."""
        m = self.m
        e0, e1 = np.asarray(eps_from, float), np.asarray(eps_to, float)
        s_of = lambda lam: m.growth(*(e0 + lam * (e1 - e0)))  # noqa: E731
        ds = m.growth(*(e1 - e0)) - 1.0                        # ∂s/∂λ per element
        lam, dlam0 = 0.0, 1.0 / nsteps
        if self.lu is None:
            self.factor(m.residual_tangent(u, s_of(0.0))[1])
        prev = None
        while lam < 1.0 - 1e-14:
            dlam = min(dlam0, 1.0 - lam)
            v = -self.solve(m.dresidual_ds(u, s_of(lam), ds))    # du/dλ at the converged state
            for _ in range(max_halvings + 1):
                s_new = s_of(lam + dlam)
                r0 = np.linalg.norm(m.residual(u, s_new))
                pred = u.copy()
                if prev is None:
                    pred[m.free] += dlam * v                          # Euler (tangent) predictor
                else:
                    # cubic Hermite extrapolation through the last two converged states and their
                    # tangents du/dλ (Hermite basis h00, h10, h01, h11 on [λ_prev, λ])
                    lp, up, vp = prev
                    H = lam - lp
                    t = 1.0 + dlam / H
                    h00, h10 = 2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t
                    h01, h11 = -2 * t**3 + 3 * t**2, t**3 - t**2
                    pred[m.free] = (h00 * up[m.free] + h10 * H * vp + h01 * u[m.free]
                                    + h11 * H * v)
                try:
                    u_new, _ = self.newton(pred, s_new, r0)
                    break
                except (NonPhysical, RuntimeError):
                    self.cuts += 1
                    dlam *= 0.5
            else:
                raise RuntimeError(f"continuation failed at λ = {lam:.6g}")
            prev = (lam, u, v)
            u, lam = u_new, lam + dlam
            self.steps += 1
        return u


def dumps(obj):
    """JSON text of obj, with numpy scalars and arrays converted."""
    return json.dumps(obj, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o))


def auto_steps(d_eps_max, per_step=0.05):
    """Default number of load steps: one per `per_step` of eigenstrain."""
    return max(1, int(math.ceil(d_eps_max / per_step - 1e-12)))


# ----------------------------------------------------------------------------------------------
# Runs
# ----------------------------------------------------------------------------------------------

def report(c: Case, model: Strip, solver: Solver, u, wall, cpu, extra=None):
    lines, kmid, thick = model.measure(u)
    kt = timoshenko_kappa(c)
    out = {
        "inputs": asdict(c),
        "ndof": model.ndof,
        "ndof_free": model.nfree,
        "elements": model.nel,
        "wall_s": round(wall, 3),
        "cpu_s": round(cpu, 3),
        "newton_iterations": solver.iterations,
        "load_steps": solver.steps,
        "step_cuts": solver.cuts,
        "final_residual_rel": solver.last_rel,
        "lines": lines,
        "kappa_mid": kmid,
        "kappa_mid_h": kmid * c.h,
        "thickness_deformed": thick,
        "kappa_timoshenko": kt,
        "kappa_mid_over_timoshenko": kmid / kt if kt != 0 else None,
    }
    if c.width_mode == "plane-strain":
        ub = uniform_bending_plane_strain(c)
        if ub is not None:
            out["uniform_bending_1d"] = ub
            out["kappa_mid_over_uniform_bending"] = kmid / ub["kappa_mid"]
    if extra:
        out.update(extra)
    return out


def run_case(c: Case, steps=0, u_init=None, model_init=None):
    """Solve one case from zero growth (or, given u_init on model_init, by Newton at full
    growth from the prolonged solution, falling back to continuation)."""
    t0, c0 = time.perf_counter(), time.process_time()
    model = Strip(c)
    solver = Solver(model)
    target = (c.eps_bottom, c.eps_top)
    u = None
    if u_init is not None:
        u0 = model.prolong(model_init, u_init)
        s = model.growth(*target)
        try:
            r0 = np.linalg.norm(model.residual(np.zeros(model.ndof), s))
            u, _ = solver.newton(u0, s, r0)
            solver.steps = 1
        except (NonPhysical, RuntimeError):
            u = None
    if u is None:
        n = steps or auto_steps(max(abs(c.eps_top), abs(c.eps_bottom),
                                    abs(c.eps_top - c.eps_bottom)))
        u = solver.continuation(np.zeros(model.ndof), (0.0, 0.0), target, n)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    return model, u, report(c, model, solver, u, wall, cpu)


def richardson(k, ratio=2.0):
    """Richardson extrapolation of three values on meshes refined by `ratio`: observed order
    p = log((k₀ − k₁)/(k₁ − k₂))/log(ratio), limit k∞ = k₂ + (k₂ − k₁)/(ratioᵖ − 1). Returns
    (p, k∞, error of the middle value k₁ − k∞); p and k∞ are None outside the asymptotic
    range (differences not shrinking monotonically), the error then bounded by |k₁ − k₂|
    plus |k₀ − k₁|."""
    d1, d2 = k[0] - k[1], k[1] - k[2]
    if d1 * d2 > 0 and abs(d1) > abs(d2):
        p = math.log(d1 / d2) / math.log(ratio)
        k_ext = k[2] + (k[2] - k[1]) / (ratio**p - 1.0)
        return p, k_ext, k[1] - k_ext
    return None, None, abs(d1) + abs(d2)


def refine_study(c: Case, steps=0):
    """Discretisation error of kappa_mid on the given (medium) mesh, by two refinement
    sequences with ratio 2 and Richardson extrapolation of each:
      along x:         (nx/2, ny, nz), (nx, ny, nz), (2nx, ny, nz);
      cross-section:   (nx/2, ny/2, nz/2), (nx/2, ny, nz), (nx/2, 2ny, 2nz)
                       (y is not refined in plane strain, whose solution does not vary in y).
    The cross-section sequence runs at nx/2 to keep its finest mesh affordable; errors of the two
    directions add (κ_h ≈ κ + e_x(nx) + e_yz(ny, nz) in the asymptotic range), so the medium
    mesh's error is estimated as e_x + e_yz and the limit as κ_medium − e_x − e_yz. Only the
    medium mesh is solved by continuation; the others start from its solution interpolated
    onto them and need a few Newton iterations at full growth."""
    ps = c.width_mode == "plane-strain"
    if c.nx % 2 or c.nz % 2 or c.nz < 4 or (not ps and c.ny % 2):
        raise ValueError("refine study needs even nx, even nz ≥ 4 and (free width) even ny")
    hx, hy = c.nx // 2, (c.ny if ps else c.ny // 2)
    fy = c.ny if ps else 2 * c.ny
    model, u, base = run_case(c, steps)
    print(dumps(base), flush=True)
    k = {}
    k[(c.nx, c.ny, c.nz)] = base["kappa_mid"]
    runs = [(hx, c.ny, c.nz), (2 * c.nx, c.ny, c.nz), (hx, hy, c.nz // 2), (hx, fy, 2 * c.nz)]
    table = [[c.nx, c.ny, c.nz, base["ndof"], base["kappa_mid"], base["wall_s"]]]
    for nx, ny, nz in runs:
        out = run_case(replace(c, nx=nx, ny=ny, nz=nz), steps, u_init=u, model_init=model)[2]
        print(dumps(out), flush=True)
        k[(nx, ny, nz)] = out["kappa_mid"]
        table.append([nx, ny, nz, out["ndof"], out["kappa_mid"], out["wall_s"]])
    kx = [k[(hx, c.ny, c.nz)], k[(c.nx, c.ny, c.nz)], k[(2 * c.nx, c.ny, c.nz)]]
    ks = [k[(hx, hy, c.nz // 2)], k[(hx, c.ny, c.nz)], k[(hx, fy, 2 * c.nz)]]
    px, _, ex = richardson(kx)
    pc, _, ec = richardson(ks)
    km = base["kappa_mid"]
    summary = {
        "refine_study": {"inputs": asdict(c), "runs [nx, ny, nz, ndof, kappa_mid, wall_s]": table},
        "x": {"kappa": kx, "observed_order": px, "error_medium": ex},
        "cross_section": {"kappa": ks, "observed_order": pc, "error_medium": ec},
        "kappa_mid_medium": km,
        "kappa_mid_extrapolated": (km - ex - ec) if px is not None and pc is not None else None,
        "rel_error_medium_estimate": (abs(ex) + abs(ec)) / abs(km),
        "kappa_timoshenko": timoshenko_kappa(c),
    }
    print(dumps(summary), flush=True)


def sweep(c: Case, mismatches=(0.05, 0.10, 0.20, 0.35, 0.50), per_step=0.05):
    """ε_top = mismatch, ε_bottom = 0. All cases lie on one proportional loading path, so each
    equilibrium is reached by continuation from the previous one (same result as a separate
    run from zero growth: the response is hyperelastic and follows one stable branch)."""
    t_all = time.perf_counter()
    base = replace(c, eps_top=0.0, eps_bottom=0.0)
    model = Strip(base)
    u = np.zeros(model.ndof)
    prev = 0.0
    solver = Solver(model)
    for mm in mismatches:
        t0, c0 = time.perf_counter(), time.process_time()
        ci = replace(c, eps_top=mm, eps_bottom=0.0)
        it0, st0, cu0 = solver.iterations, solver.steps, solver.cuts
        u = solver.continuation(u, (0.0, prev), (0.0, mm), auto_steps(mm - prev, per_step))
        out = report(ci, model, solver, u, time.perf_counter() - t0, time.process_time() - c0,
                     {"wall_cumulative_s": round(time.perf_counter() - t_all, 3),
                      "newton_iterations_segment": solver.iterations - it0,
                      "load_steps_segment": solver.steps - st0,
                      "step_cuts_segment": solver.cuts - cu0})
        print(dumps(out), flush=True)
        prev = mm


def check_tangent(c: Case, seed=0):
    """Central finite differences on a small mesh at a large-deformation state (the case's
    growth, then a random perturbation of 0.01 h): K v against (R(u+hv) − R(u−hv))/2h,
    R·v against the energy's difference, and ∂R/∂λ against the residual's difference in λ."""
    ci = replace(c, nx=6, ny=2, nz=2, L=min(c.L, 6.0 * c.h))
    model = Strip(ci)
    solver = Solver(model)
    target = (ci.eps_bottom, ci.eps_top)
    u = solver.continuation(np.zeros(model.ndof), (0.0, 0.0), target,
                            auto_steps(abs(ci.eps_top - ci.eps_bottom)))
    rng = np.random.default_rng(seed)
    u[model.free] += 0.01 * ci.h * rng.standard_normal(model.nfree)
    s = model.growth(*target)
    R, K = model.residual_tangent(u, s)
    v = rng.standard_normal(model.nfree)
    Kv = K @ v
    out = {"check_tangent": True, "inputs": asdict(ci), "ndof_free": model.nfree,
           "K_symmetry": float(abs(K - K.T).max() / abs(K).max()), "rows": []}

    def shifted(hh):
        w = u.copy()
        w[model.free] += hh * v
        return w
    ds = model.growth(*target) - 1.0            # path s(λ) = 1 + λ ε, at λ = 1
    dRdl = model.dresidual_ds(u, s, ds)
    for hh in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7):
        fd_R = (model.residual(shifted(hh), s) - model.residual(shifted(-hh), s)) / (2 * hh)
        fd_E = (model.energy(shifted(hh), s) - model.energy(shifted(-hh), s)) / (2 * hh)
        fd_l = (model.residual(u, model.growth(*(np.array(target) * (1 + hh))))
                - model.residual(u, model.growth(*(np.array(target) * (1 - hh))))) / (2 * hh)
        out["rows"].append({
            "fd_step": hh,
            "tangent_rel_err": float(np.linalg.norm(Kv - fd_R) / np.linalg.norm(Kv)),
            "gradient_rel_err": float(abs(R @ v - fd_E) / abs(R @ v)),
            "dR_dlambda_rel_err": float(np.linalg.norm(dRdl - fd_l) / np.linalg.norm(dRdl)),
        })
    print(dumps(out), flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--h", type=float, default=1.0, help="total thickness")
    ap.add_argument("--L", type=float, default=None, help="length (default 20 h)")
    ap.add_argument("--W", type=float, default=None, help="width (default h)")
    ap.add_argument("--phi", type=float, default=0.5,
                    help="top layer's thickness fraction (default 0.5)")
    ap.add_argument("--n", type=float, default=1.0, help="modulus ratio E_top/E_bottom")
    ap.add_argument("--nu", type=float, default=0.3, help="Poisson ratio of both layers")
    ap.add_argument("--Eb", type=float, default=1.0, help="bottom layer's Young's modulus")
    ap.add_argument("--eps-top", type=float, default=0.1,
                    help="top layer's swelling strain: s_top = 1 + eps_top (default 0.1)")
    ap.add_argument("--eps-bottom", type=float, default=0.0,
                    help="bottom layer's swelling strain (default 0)")
    ap.add_argument("--material", choices=sorted(MATERIALS), default="neo-hookean")
    ap.add_argument("--width-mode", choices=["free", "plane-strain"], default="free",
                    help="side faces free (narrow 3D strip) or u_y = 0 on them")
    ap.add_argument("--nx", type=int, default=40, help="elements along x over L/2 (default 40)")
    ap.add_argument("--ny", type=int, default=None,
                    help="elements across the half width W/2 (default 2 free, 1 plane strain)")
    ap.add_argument("--nz", type=int, default=8,
                    help="elements through the thickness, split between the layers (default 8)")
    ap.add_argument("--grade", type=float, default=None,
                    help="mesh grading 0..1 toward the interface and the free side face "
                         "(default 1 free, 0 plane strain)")
    ap.add_argument("--steps", type=int, default=0,
                    help="load steps (default: one per 0.05 of eigenstrain)")
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--check-tangent", action="store_true",
                      help="finite-difference check of the tangent, gradient and ∂R/∂λ")
    mode.add_argument("--refine-study", action="store_true",
                      help="discretisation error of kappa_mid by Richardson extrapolation")
    mode.add_argument("--sweep", action="store_true",
                      help="eps_top = 0.05, 0.1, 0.2, 0.35, 0.5 with eps_bottom = 0")
    a = ap.parse_args(argv)
    ps = a.width_mode == "plane-strain"
    if a.ny is None:
        a.ny = 1 if ps else 2
    if a.grade is None:
        a.grade = 0.0 if ps else 1.0
    c = Case(h=a.h, L=20.0 * a.h if a.L is None else a.L, W=a.h if a.W is None else a.W,
             phi=a.phi, n=a.n, nu=a.nu, Eb=a.Eb, eps_top=a.eps_top, eps_bottom=a.eps_bottom,
             material=a.material, width_mode=a.width_mode, nx=a.nx, ny=a.ny, nz=a.nz,
             grade=a.grade)
    if a.check_tangent:
        check_tangent(c)
    elif a.refine_study:
        refine_study(c, a.steps)
    elif a.sweep:
        sweep(c)
    else:
        print(dumps(run_case(c, a.steps)[2]), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
