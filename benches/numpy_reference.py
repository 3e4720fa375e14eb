"""An independent, vectorised numpy/scipy implementation of hvi's scheme (docs/method.md §2-§5) for the
paper's example (docs/example.md, with the readings of examples/paper.toml): the reference that hvi's
whole-run time is measured against (benches/whole_run_vs_numpy.py).

Q1 elements on the structured nx x ny mesh of (0,2)x(0,1), plane stress E = 1, nu = 0.3, memory
B(s) = (0.5+s)^2 I, traction (0, -0.1(1-e^{-2t})x) on y = 1, clamped at x = 0 (dofs eliminated),
contact on y = 0 (nu = (0,-1), g = 0.2, the paper's odd compliance law regularised with
eps = 1e-8, nodal weights), trapezoidal history by shifted polynomial moments, T = 1. K = K_A +
(k/2) b(0) K_B is factored once with scipy's SuperLU (splu), W = C K^-1 C^T is dense, and each step
solves the condensed contact problem by a projected Newton / active-set method with an Armijo line
search on the energy (the globalisation of src/contact/newton.rs), warm-started from the last
step. Vectorised: Python loops run only over time steps, Newton iterations and line-search cuts.

    python3 benches/numpy_reference.py --nx 256 --ny 128 --steps 128 [--out FILE.npz]

splu uses permc_spec=MMD_AT_PLUS_A with SymmetricMode and diag_pivot_thresh=0 (the fastest of
the four orderings here: least fill, fastest factor and solves), W in blocks of 32 right-hand sides,
one BLAS thread unless OPENBLAS_NUM_THREADS is set. --prune drops the entries of K that cancel in
exact arithmetic on the uniform grid (about 28 %: less fill, faster solves; off by default, since
hvi factors the full Q1 pattern). Prints per-phase wall times and Newton iterations; --out saves
the final nodal displacement `u` (node j*(nx+1)+i at (2i/nx, j/ny), as hvi's rect:NXxNY) and the
Newton iterations per step.
Needs numpy and scipy only (pip install numpy scipy).
"""
import argparse
import math
import os
import time

T0 = time.perf_counter()
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one BLAS thread, like hvi: 2 made SuperLU's block solves erratic
try:
    import numpy as np
    import scipy.linalg as sla
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
except ImportError as e:  # pragma: no cover
    raise SystemExit(f"numpy_reference.py needs numpy and scipy ({e}): pip install numpy scipy")

E, NU = 1.0, 0.3                       # plane stress
B_COEF = [0.25, 1.0, 1.0]              # b(s) = (0.5 + s)^2 = 0.25 + s + s^2
S, A_, B_, ALPHA, EPS, G = 0.1, 0.04, 0.02, 100.0, 1e-8, 0.2
TOL, MAX_IT, ARMIJO, MIN_STEP = 1e-10, 100, 1e-4, 1e-12


def assemble(nx, ny, lx=2.0, ly=1.0):
    """K_A, K_B (free dofs, CSC), the free-dof map and the node coordinates."""
    xs, ys = np.meshgrid(np.linspace(0, lx, nx + 1), np.linspace(0, ly, ny + 1))
    pts = np.column_stack([xs.ravel(), ys.ravel()])
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    a = (i + j * (nx + 1)).ravel()
    cells = np.column_stack([a, a + 1, a + nx + 2, a + nx + 1])           # counter-clockwise
    g = 1 / np.sqrt(3)
    c = E / (1 - NU**2)
    d_a = np.array([[c, c * NU, 0], [c * NU, c, 0], [0, 0, c * (1 - NU) / 2]])
    d_b = np.diag([1.0, 1.0, 0.5])                                         # (B0 e, t) = e : t
    xe = pts[cells]                                                        # (cells, 4, 2)
    ka = kb = 0.0
    for xi, eta in [(-g, -g), (g, -g), (g, g), (-g, g)]:
        dn = 0.25 * np.array([[-(1 - eta), (1 - eta), (1 + eta), -(1 + eta)],
                              [-(1 - xi), -(1 + xi), (1 + xi), (1 - xi)]])  # dN/d(xi,eta)
        jac = np.einsum("rk,ekd->erd", dn, xe)                             # (cells, 2, 2)
        det = np.linalg.det(jac)
        grad = np.linalg.solve(jac, np.broadcast_to(dn, (len(cells), 2, 4)))  # dN/dx
        bm = np.zeros((len(cells), 3, 8))
        bm[:, 0, 0::2] = grad[:, 0]
        bm[:, 1, 1::2] = grad[:, 1]
        bm[:, 2, 0::2] = grad[:, 1]
        bm[:, 2, 1::2] = grad[:, 0]
        bt = bm.transpose(0, 2, 1) * det[:, None, None]
        ka = ka + bt @ (d_a @ bm)
        kb = kb + bt @ (d_b @ bm)
    n_nodes = len(pts)
    free = np.full(2 * n_nodes, -1)
    keep = np.repeat(pts[:, 0] > 0, 2)                                    # Gamma1: x = 0 clamped
    free[keep] = np.arange(keep.sum())
    edofs = free[(2 * cells[:, :, None] + np.arange(2)).reshape(len(cells), 8)]
    ka, kb = 0.5 * (ka + ka.transpose(0, 2, 1)), 0.5 * (kb + kb.transpose(0, 2, 1))
    rows = np.broadcast_to(edofs[:, :, None], ka.shape).ravel()
    cols = np.broadcast_to(edofs[:, None, :], ka.shape).ravel()
    ok = (rows >= 0) & (cols >= 0)
    n = int(keep.sum())
    mats = [sp.csc_matrix((k.ravel()[ok], (rows[ok], cols[ok])), shape=(n, n)) for k in (ka, kb)]
    return mats[0], mats[1], free, pts


class Law:
    """The paper's odd law j(r) = S phi(rho(r)), rho(r) = sqrt(r^2+eps^2) - eps (law.rs)."""
    @staticmethod
    def eval(r):
        root = np.hypot(r, EPS)
        s, ds, dds = r * r / (root + EPS), r / root, EPS * EPS / root**3
        ex = np.exp(-ALPHA * s)
        phi = B_ * s - (A_ - B_) * np.expm1(-ALPHA * s) / ALPHA
        mu, dmu = (A_ - B_) * ex + B_, -ALPHA * (A_ - B_) * ex
        return S * phi, S * mu * ds, S * (dmu * ds * ds + mu * dds)


def contact_solve(q, cq, w, d, r, stats):
    """min 1/2 (r-d)'Q(r-d) + sum w j(r) s.t. r <= g; returns r (u_nu at the contact nodes)."""
    r = np.minimum(r, G)
    grad_of = lambda x: q @ (x - d) + w * Law.eval(x)[1]
    resid_of = lambda x, gr: np.abs(np.minimum(cq * (G - x), -gr)).max()
    scale = max(np.abs(q @ d).max(), S * max(A_, B_) * w.max(), 1e-308)
    tol, best, its = TOL * scale, np.inf, 0
    while True:
        grad = grad_of(r)
        res = resid_of(r, grad)
        best = min(best, res)
        if res <= tol:
            break
        if its == MAX_IT:
            raise RuntimeError(f"contact: no convergence in {MAX_IT} iterations")
        its += 1
        pstep = np.abs(r - np.minimum(r - grad / cq, G)).max()
        delta = min(pstep, 1e-3 * max(G, 1e-3))
        active = (r - grad / cq >= G) | ((G - r <= delta) & (grad < 0))
        fr = ~active
        direction = np.where(active, grad / cq, 0.0)
        if fr.any():
            curv = w[fr] * Law.eval(r[fr])[2]
            qff = q[np.ix_(fr, fr)]
            try:
                direction[fr] = sla.cho_solve((np.linalg.cholesky(qff + np.diag(curv)), True), grad[fr])
            except np.linalg.LinAlgError:                                  # indefinite: convexify
                stats["convexified"] += 1
                shift = 0.0
                while True:
                    try:
                        lf = np.linalg.cholesky(qff + np.diag(np.maximum(curv, 0) + shift))
                        break
                    except np.linalg.LinAlgError:
                        shift = 1e-12 * cq[fr][0] if shift == 0 else 10 * shift
                direction[fr] = sla.cho_solve((lf, True), grad[fr])
        slope = grad[fr] @ direction[fr]
        j0, j1, j2 = Law.eval(r)
        alpha = 1.0
        while True:                                                        # projected Armijo
            step = r - alpha * direction
            moved = np.minimum(step, G)
            kink = fr & (np.abs(r) > EPS) & (moved * r < 0)                # stop at the kink r = 0
            bound = alpha * slope + grad[kink] @ step[kink]
            moved[kink] = 0.0
            trial = moved - r
            bound -= grad[active] @ trial[active]
            small = np.abs(trial) <= 1e-4 * np.maximum(np.abs(r), EPS)
            rest = np.where(small, 0.5 * j2 * trial**2, Law.eval(moved)[0] - j0 - j1 * trial)
            change = trial @ (grad + 0.5 * (q @ trial)) + w @ rest
            if change <= -ARMIJO * bound or (change <= 0 and bound <= 1e-300):
                break
            if alpha == 1.0 and resid_of(moved, grad_of(moved)) <= 0.5 * best:
                break
            alpha *= 0.5
            stats["cuts"] += 1
            if alpha < MIN_STEP:
                if res <= 100 * tol:
                    return r, its
                raise RuntimeError("contact: the line search could not decrease the energy")
        r = np.minimum(r + trial, G)
    return r, its


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--nx", type=int, default=256)
    ap.add_argument("--ny", type=int, default=128)
    ap.add_argument("--steps", type=int, default=128)
    ap.add_argument("--permc", default="MMD_AT_PLUS_A",
                    help="splu permc_spec: NATURAL, MMD_ATA, MMD_AT_PLUS_A, COLAMD")
    ap.add_argument("--block", type=int, default=32, help="right-hand sides per solve when forming W")
    ap.add_argument("--prune", action="store_true", help="drop round-off entries of K before splu")
    ap.add_argument("--out", help="save the final nodal displacement to this .npz")
    args = ap.parse_args()
    nx, ny, steps = args.nx, args.ny, args.steps
    k = 1.0 / steps
    times = {"import": time.perf_counter() - T0}
    tic = time.perf_counter()

    k_a, k_b, free, pts = assemble(nx, ny)
    n = k_a.shape[0]
    assert np.array_equal(k_a.indices, k_b.indices) and np.array_equal(k_a.indptr, k_b.indptr)
    kmat = sp.csc_matrix((k_a.data + (0.5 * k * B_COEF[0]) * k_b.data, k_a.indices, k_a.indptr), k_a.shape)
    if args.prune:                       # drop entries that cancel in exact arithmetic (uniform grid)
        kmat.data[np.abs(kmat.data) < 1e-14 * np.abs(kmat.data).max()] = 0.0
        kmat.eliminate_zeros()
    # traction on y = 1: 3-point Gauss on each top edge (src/fem/loads.rs)
    top = np.arange(nx) + ny * (nx + 1)
    sq, wq = np.array([0.5 - 0.5 * np.sqrt(0.6), 0.5, 0.5 + 0.5 * np.sqrt(0.6)]), np.array([5, 8, 5]) / 18
    xa, xb = pts[top, 0], pts[top + 1, 0]
    xq = (1 - sq) * xa[:, None] + sq * xb[:, None]
    wts = wq * (xb - xa)[:, None]
    ydof = free[2 * np.concatenate([np.repeat(top, 3), np.repeat(top + 1, 3)]) + 1]
    shape = np.concatenate([np.tile(1 - sq, nx), np.tile(sq, nx)])
    ok = ydof >= 0

    def load(t):
        fy = np.tile((-0.1 * (1 - np.exp(-2 * t)) * xq * wts).ravel(), 2) * shape
        return np.bincount(ydof[ok], fy[ok], minlength=n)

    # contact nodes: y = 0, x > 0; u_nu = -u_y; weights = half of each adjacent edge
    bot = np.arange(1, nx + 1)
    cdof = free[2 * bot + 1]
    m = len(bot)
    hx = 2.0 / nx
    w = np.full(m, hx)
    w[-1] = 0.5 * hx
    csp = sp.csr_matrix((-np.ones(m), (np.arange(m), cdof)), shape=(m, n))
    times["assembly"] = time.perf_counter() - tic

    def operator(mat):
        t0 = time.perf_counter()
        lu = spla.splu(mat, permc_spec=args.permc, diag_pivot_thresh=0.0,
                       options=dict(SymmetricMode=True))
        t1 = time.perf_counter()
        wmat = np.empty((m, m))
        for s0 in range(0, m, args.block):                                 # blocks of rhs
            z = np.zeros((n, min(args.block, m - s0)), order="F")
            z[cdof[s0:s0 + args.block], np.arange(z.shape[1])] = -1.0
            wmat[:, s0:s0 + z.shape[1]] = csp @ lu.solve(z)
        wmat = 0.5 * (wmat + wmat.T)
        q = sla.cho_solve(sla.cho_factor(wmat), np.eye(m))
        q = 0.5 * (q + q.T)
        return lu, q, np.diag(q).copy(), t1 - t0, time.perf_counter() - t1

    lu, q, cq, times["factorisation"], times["condensation"] = operator(kmat)
    times["factor_nnz"] = lu.L.nnz + lu.U.nnz

    tic = time.perf_counter()
    stats = {"cuts": 0, "convexified": 0}
    moments = np.zeros((len(B_COEF), n))                                   # P_j = sum w_i (t_n-t_i)^j u_i
    r = np.zeros(m)
    u = np.zeros(n)
    iters = [0]
    f0 = load(0.0)
    if np.any(f0 != 0):          # step 0: K_A alone, no history (here F_0 = 0 and j'(0) = 0: u_0 = 0)
        lu0, q0, cq0, *_ = operator(k_a.tocsc())
        uf = lu0.solve(f0)
        r, it = contact_solve(q0, cq0, w, csp @ uf, r, stats)
        u = lu0.solve(f0 - csp.T @ (q0 @ (csp @ uf - r)))
        iters[0] = it
    for step in range(steps + 1):
        if step > 0:
            h = k * (np.asarray(B_COEF) @ moments)
            rhs = load(step * k) - k_b @ h
            uf = lu.solve(rhs)
            d = csp @ uf
            r, it = contact_solve(q, cq, w, d, r, stats)
            lam = q @ (d - r)
            u = lu.solve(rhs - csp.T @ lam)
            iters.append(it)
        moments[0] += (0.5 if step == 0 else 1.0) * u                      # history push
        for j in range(len(B_COEF) - 1, 0, -1):
            for l_ in range(j):
                moments[j] += math.comb(j, l_) * k ** (j - l_) * moments[l_]
    times["steps"] = time.perf_counter() - tic
    times["total"] = time.perf_counter() - T0

    print(f"numpy reference: {nx}x{ny} Q1, {n} unknowns, {m} contact nodes, {steps} steps, "
          f"splu permc_spec={args.permc} (L+U nnz {times['factor_nnz']})")
    phases = ["import", "assembly", "factorisation", "condensation", "steps", "total"]
    print("time [s]: " + ", ".join(f"{key} {times[key]:.3f}" for key in phases))
    print(f"Newton iterations: {sum(iters)} in all (max {max(iters)} per step), line-search cuts "
          f"{stats['cuts']}, convexified {stats['convexified']}, {int((r >= G).sum())} on the bound at T")
    if args.out:
        nodal = np.zeros(2 * len(pts))
        nodal[free >= 0] = u
        np.savez(args.out, u=nodal.reshape(-1, 2), points=pts, newton=np.array(iters), u_nu=r,
                 times=np.array([times[key] for key in phases]))


if __name__ == "__main__":
    main()
