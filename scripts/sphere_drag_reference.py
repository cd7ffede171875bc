#!/usr/bin/env python3
"""The drag of a sphere in a steady uniform flow, computed on a body-fitted
grid: the reference for the settling sphere's terminal Reynolds number
(docs/validation.md, §7 and §10) that does not depend on a correlation.

The steady axisymmetric Navier-Stokes equations in Stokes's stream function
psi and the azimuthal vorticity w, lengths in sphere radii a, speeds in the
far stream U, Re_a = U a / nu = Re / 2 (Re on the diameter):

    E^2 psi = -r sin(theta) w,
    u . grad w - w u_s / s = (1/Re_a) (lap w - w / s^2),      s = r sin(theta),

with E^2 = d_rr + (sin(theta)/r^2) d_theta (1/sin(theta) d_theta), the
stretching term w u_s / s of a vortex ring that grows, and
u_r = psi_theta / (r^2 sin(theta)), u_theta = -psi_r / (r sin(theta)).
Grid: xi = ln r uniform on [0, ln r_max], theta uniform on [0, pi], second
order central differences throughout, solved by Newton's method on the
coupled system (sparse LU). No slip at r = 1 (psi = 0, w from psi with
Jensen's second-order wall formula w = -(8 psi_1 - psi_2)/(2 h^2 sin)),
psi = 0 and w = 0 on the axis, the uniform stream psi = r^2 sin^2/2 at
r_max, w = 0 upstream there and dw/dr = 0 downstream.

The drag: the wall shear is mu w, the wall pressure follows from the
tangential momentum at the wall, dp/dtheta = mu (w + dw/dr), and

    F_z = 2 pi a^2 int_0^pi (-p cos(theta) - mu w sin(theta)) sin(theta) dtheta,
    C_D = F_z / (rho U^2 pi a^2 / 2).

Stokes's flow gives w = -1.5 sin(theta)/r^2 and C_D = 24/Re exactly; the
script checks the Oseen limit C_D = (24/Re)(1 + 3 Re/16) at Re = 0.1.

    scripts/sphere_drag_reference.py --re 0.1 20 100 --grids 100x80 200x160 400x320
    scripts/sphere_drag_reference.py --archimedes 800 \
        --grids 100x320 200x320 400x320 800x320 --r-max 100 200 \
        --out docs/validation/sphere_drag_reference.csv

With --archimedes Ar = rho (rho_p - rho) g D^3 / mu^2 the script finds the
terminal Reynolds number of a sphere settling freely in an unbounded
fluid, C_D(Re) Re^2 = (4/3) Ar, on each grid, and extrapolates in the grid
(Richardson, with the order the last three grids show). The polar
direction converges at second order and is fine enough at 320 cells; the
radial one approaches second order from about 1.5 (the wall's vorticity).
"""
import argparse
import csv
import math
import sys

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla


class Grid:
    def __init__(self, radial, polar, r_max):
        self.nr, self.nt = radial, polar
        self.h = math.log(r_max) / radial
        self.k = math.pi / polar
        xi = np.arange(radial + 1) * self.h
        theta = np.arange(polar + 1) * self.k
        # Node (j, i) at index j * (nt + 1) + i: xi along j, theta along i.
        self.xi, self.theta = np.meshgrid(xi, theta, indexing="ij")
        self.n = (radial + 1) * (polar + 1)
        s = np.sin(self.theta)
        s[:, 0] = s[:, -1] = 1.0  # the axis rows are boundary rows
        self.sin = s.ravel()
        self.cos = np.cos(self.theta).ravel()
        self.r = np.exp(self.xi).ravel()
        j, i = np.meshgrid(np.arange(radial + 1), np.arange(polar + 1), indexing="ij")
        self.j, self.i = j.ravel(), i.ravel()
        self.interior = (self.j > 0) & (self.j < radial) & (self.i > 0) & (self.i < polar)
        self.dxi = self._difference(1, 0, self.h, second=False)
        self.dxixi = self._difference(1, 0, self.h, second=True)
        self.dth = self._difference(0, 1, self.k, second=False)
        self.dthth = self._difference(0, 1, self.k, second=True)

    def index(self, j, i):
        return j * (self.nt + 1) + i

    def _difference(self, dj, di, step, second):
        """Central first or second differences at the interior nodes (rows of
        other nodes empty)."""
        rows = np.flatnonzero(self.interior)
        plus = self.index(self.j[rows] + dj, self.i[rows] + di)
        minus = self.index(self.j[rows] - dj, self.i[rows] - di)
        if second:
            data = np.concatenate([np.full(rows.size, 1.0), np.full(rows.size, -2.0),
                                   np.full(rows.size, 1.0)]) / step**2
            cols = np.concatenate([plus, rows, minus])
            rr = np.concatenate([rows, rows, rows])
        else:
            data = np.concatenate([np.full(rows.size, 0.5), np.full(rows.size, -0.5)]) / step
            cols = np.concatenate([plus, minus])
            rr = np.concatenate([rows, rows])
        return sp.csr_matrix((data, (rr, cols)), shape=(self.n, self.n))


def solve(grid, re_a, guess=None, tolerance=1e-12, max_newton=30):
    g = grid
    n = g.n
    s, c, r = g.sin, g.cos, g.r
    inner = g.interior.astype(float)
    cot = inner * c / s
    dxi, dxixi, dth, dthth = g.dxi, g.dxixi, g.dth, g.dthth
    diag = sp.diags
    # Linear parts of the two equations (interior rows), multiplied by r^2.
    stream_psi = dxixi - dxi + dthth - diag(cot) @ dth
    stream_w = diag(inner * r**3 * s)
    vort_w = dxixi + dxi + dthth + diag(cot) @ dth - diag(inner / s**2)
    # Boundary rows.
    wall = g.j == 0
    axis = ((g.i == 0) | (g.i == g.nt)) & ~wall
    outer = (g.j == g.nr) & ~axis
    downstream = outer & (c > 0)
    eye_b = lambda mask: diag(mask.astype(float))
    far_psi = np.where(outer, 0.5 * r**2 * s**2, 0.0)
    psi_rows_b = eye_b(wall | axis | outer)
    # Wall vorticity: w_0 sin + (8 psi_1 - psi_2) / (2 h^2) = 0 (off the axis).
    wall_nodes = np.flatnonzero(wall & ~((g.i == 0) | (g.i == g.nt)))
    wall_psi = sp.csr_matrix(
        (np.concatenate([np.full(wall_nodes.size, 8.0), np.full(wall_nodes.size, -1.0)])
         / (2 * g.h**2),
         (np.concatenate([wall_nodes, wall_nodes]),
          np.concatenate([wall_nodes + (g.nt + 1), wall_nodes + 2 * (g.nt + 1)]))),
        shape=(n, n))
    wall_w = sp.csr_matrix((s[wall_nodes], (wall_nodes, wall_nodes)), shape=(n, n))
    # The axis (and the wall's ends on it): w = 0; upstream far field w = 0;
    # downstream dw/dxi = 0.
    w_zero = eye_b((axis | (wall & ((g.i == 0) | (g.i == g.nt))) | (outer & ~downstream)))
    down_nodes = np.flatnonzero(downstream)
    w_down = sp.csr_matrix(
        (np.concatenate([np.ones(down_nodes.size), -np.ones(down_nodes.size)]),
         (np.concatenate([down_nodes, down_nodes]),
          np.concatenate([down_nodes, down_nodes - (g.nt + 1)]))), shape=(n, n))
    w_rows_b = wall_w + w_zero + w_down
    advect = re_a * inner / r

    if guess is None:
        # Stokes's flow.
        f = 0.5 * (r**2 - 1.5 * r + 0.5 / r)
        psi = f * np.sin(g.theta.ravel())**2
        w = -1.5 * np.sin(g.theta.ravel()) / r**2
        psi = np.where(outer, far_psi, psi)
    else:
        psi, w = guess
    for iteration in range(max_newton):
        psi_xi, psi_th = dxi @ psi, dth @ psi
        w_xi, w_th = dxi @ w, dth @ w
        stretch = (psi_th * s - psi_xi * c) / s**2
        transport = advect * ((psi_th * w_xi - psi_xi * w_th) / s - w * stretch)
        res_psi = stream_psi @ psi + stream_w @ w + psi_rows_b @ psi - far_psi
        res_w = vort_w @ w - transport + w_rows_b @ w + wall_psi @ psi
        residual = np.concatenate([res_psi, res_w])
        norm = np.max(np.abs(residual))
        d_transport_w = (diag(advect * psi_th / s) @ dxi - diag(advect * psi_xi / s) @ dth
                         - diag(advect * stretch))
        d_transport_psi = (diag(advect * w_xi / s) @ dth - diag(advect * w_th / s) @ dxi
                           - diag(advect * w / s) @ dth + diag(advect * w * c / s**2) @ dxi)
        jacobian = sp.bmat([
            [stream_psi + psi_rows_b, stream_w],
            [wall_psi - d_transport_psi, vort_w - d_transport_w + w_rows_b],
        ], format="csc")
        step = spla.spsolve(jacobian, -residual)
        psi = psi + step[:n]
        w = w + step[n:]
        # Converged when the update is at round-off of the fields.
        if (np.max(np.abs(step[n:])) < tolerance * max(1.0, np.max(np.abs(w)))
                and np.max(np.abs(step[:n])) < tolerance * np.max(np.abs(psi))):
            break
    else:
        raise RuntimeError(f"Newton did not converge at Re_a = {re_a}: residual {norm:.3e}")
    return psi, w, iteration


def drag_coefficient(grid, re_a, w):
    """C_D on the diameter, from the wall vorticity and its normal derivative."""
    g = grid
    field = w.reshape(g.nr + 1, g.nt + 1)
    theta = g.theta[0]
    w0 = field[0]
    # dw/dr at r = 1 (= dw/dxi there), second-order one-sided.
    w_r = (-3 * field[0] + 4 * field[1] - field[2]) / (2 * g.h)
    mu = 1.0 / re_a
    dp = mu * (w0 + w_r)
    # p(theta) - p(0) by the trapezoidal rule (second order).
    p = np.concatenate([[0.0], np.cumsum(0.5 * (dp[1:] + dp[:-1]) * g.k)])
    integrand = (-p * np.cos(theta) - mu * w0 * np.sin(theta)) * np.sin(theta)
    force = 2 * math.pi * np.trapezoid(integrand, theta)
    return force / (0.5 * math.pi)


def drag_on(grid, re, guess=None):
    psi, w, iterations = solve(grid, re / 2, guess)
    return drag_coefficient(grid, re / 2, w), (psi, w), iterations


def parse_grid(text):
    radial, polar = text.lower().split("x")
    return int(radial), int(polar)


def terminal_reynolds(grid, archimedes, start, guess=None):
    """Re with C_D(Re) Re^2 = 4 Ar / 3, by the secant method on ln Re."""
    target = 4.0 * archimedes / 3.0
    re0 = start
    cd0, state, _ = drag_on(grid, re0, guess)
    f0 = math.log(cd0 * re0**2 / target)
    re1 = re0 * math.exp(-0.5 * f0)  # C_D Re^2 grows about as Re^1.5 here
    for _ in range(30):
        cd1, state, _ = drag_on(grid, re1, state)
        f1 = math.log(cd1 * re1**2 / target)
        if abs(f1) < 1e-12:
            break
        slope = (f1 - f0) / (math.log(re1) - math.log(re0))
        re0, f0 = re1, f1
        re1 = re1 * math.exp(-f1 / slope)
    return re1, cd1, state


def extrapolate(values):
    """Richardson extrapolation of a sequence on grids each twice as fine as
    the last: with the order observed over the last three where there are
    three (and it is positive), else second order."""
    if len(values) >= 3:
        a, b, c = values[-3:]
        if (b - a) * (c - b) > 0 and abs(c - b) < abs(b - a):
            ratio = (b - a) / (c - b)
            return c + (c - b) / (ratio - 1.0), math.log2(ratio)
    return values[-1] + (values[-1] - values[-2]) / 3.0, 2.0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--re", type=float, nargs="*", default=[],
                        help="Reynolds numbers (on the diameter) at which to print C_D")
    parser.add_argument("--archimedes", type=float, help="find the terminal Re at this Ar")
    parser.add_argument("--grids", nargs="+", default=["100x320", "200x320", "400x320"],
                        help="radial x polar cells, each twice the last for extrapolation")
    parser.add_argument("--r-max", type=float, nargs="+", default=[100.0],
                        help="outer radii in sphere radii")
    parser.add_argument("--out", help="CSV of the figures, one row per grid")
    args = parser.parse_args()

    rows = []
    for r_max in args.r_max:
        terminal = []
        for text in args.grids:
            radial, polar = parse_grid(text)
            grid = Grid(radial, polar, r_max)
            guess = None
            for re in args.re:
                cd, guess, iterations = drag_on(grid, re, guess)
                oseen = 24 / re * (1 + 3 * re / 16)
                sn = 24 / re * (1 + 0.15 * re**0.687)
                print(f"grid {text} r_max {r_max:g}: Re {re:g} C_D {cd:.6f} "
                      f"(Oseen {oseen:.4f}, Schiller-Naumann {sn:.4f}; {iterations} Newton steps)")
                rows.append({"grid": text, "r_max": r_max, "reynolds": re,
                             "drag_coefficient": cd})
            if args.archimedes:
                re, cd, _ = terminal_reynolds(grid, args.archimedes, 19.7)
                print(f"grid {text} r_max {r_max:g}: Ar {args.archimedes:g} terminal Re "
                      f"{re:.5f}, C_D {cd:.6f}")
                rows.append({"grid": text, "r_max": r_max, "archimedes": args.archimedes,
                             "reynolds": re, "drag_coefficient": cd})
                terminal.append(re)
            sys.stdout.flush()
        if len(terminal) >= 2:
            extrapolated, order = extrapolate(terminal)
            print(f"r_max {r_max:g}: terminal Re extrapolated in the grid {extrapolated:.5f} "
                  f"(order {order:.2f})")
            rows.append({"grid": f"extrapolated (order {order:.2f})", "r_max": r_max,
                         "archimedes": args.archimedes, "reynolds": extrapolated})
    if args.out:
        fields = ["grid", "r_max", "archimedes", "reynolds", "drag_coefficient"]
        with open(args.out, "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=fields)
            writer.writeheader()
            for row in rows:
                writer.writerow({k: row.get(k, "") for k in fields})


if __name__ == "__main__":
    main()
