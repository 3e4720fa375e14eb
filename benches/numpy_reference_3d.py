"""An independent, vectorised numpy/scipy/CHOLMOD implementation of hvi's scheme in 3D: the peer that
hvi's whole-run time on the 3D slab is measured against (benches/whole_run_vs_numpy_3d.py). Written
from the mathematics, not from the Rust code; the 2D peer is benches/numpy_reference.py.

The problem: the slab (0,2)x(0,1)x(0,Lz), Lz = 0.25, a structured grid of cubic Q1 hexahedra of
size h = 1/n (2n x n x n/4 cells), trilinear shape functions, 2x2x2 Gauss points; isotropic
elasticity A (E = 1, nu = 0.3), memory B(s) = (0.5+s)^2 I (B0 e = e); x = 0 clamped, u_z = 0 on both
z faces, every constrained component eliminated; traction (0, -0.1(1-e^{-2t})x, 0) on y = 1 (2x2
Gauss on each face); contact on y = 0 (nu = (0,-1,0), u_nu = -u_y, lumped face-mass weights, bound
g = 0.2, the paper's odd normal-compliance law regularised with eps = 1e-8); trapezoidal history
by the exact shifted polynomial moments; T = 1, k = T/N.

Linear algebra. K = K_A + (k/2) b(0) K_B is factored once by CHOLMOD (supernodal, LL'), in an
order that puts the m contact normal unknowns (the u_y of the contact nodes) LAST: the fill-reducing
ordering (--ordering) is computed by CHOLMOD on K_ii (the other unknowns), the contact unknowns are
appended, and the permuted K is factored with CHOLMOD's natural ordering. The trailing m x m block
L_cc of the factor then gives the condensed stiffness Q = W^-1 = S = K_cc - K_ci K_ii^-1 K_ic =
L_cc L_cc' with no extra solve. L_cc is read in place from the last supernodes of CHOLMOD's factor
(through ctypes: sksparse exposes no such access, and its L() copies the whole factor twice, some
seconds at n = 48); the layout is checked, with L() as the fallback (--lcc copy forces it).
One sparse solve per step: y = L^-1 b (forward), the free contact displacement is
-L_cc^-T y_c (dense m x m triangular solve), the contact problem gives u_nu = r, so the contact
unknowns u_c = -r are known; replacing y_c by L_cc' u_c and solving L' x = [y_i; L_cc' u_c]
(backward) gives the displacement of the whole body, since the back substitution for the trailing
block returns u_c and the rest is K_ii^-1 (b_i - K_ic u_c). The contact problem
min 1/2 (r-d)'Q(r-d) + sum w_p j_eps(r_p) s.t. r <= g is solved by a projected (active-set) Newton
method with Armijo backtracking along the projection arc (the arc also stops at the kink r = 0),
Hessian Q_FF + diag(w max(j'',0)) on the free set, its dense Cholesky reused while the free set and
the curvature do not change, warm-started from the last step, to 1e-10 in the relative
complementarity residual. Python loops run only over time steps, Newton iterations and cuts.

    python3 benches/numpy_reference_3d.py --n 32 --steps 32 [--save out.npy] [--ordering best|amd|metis|nesdis|default]

--save writes the final nodal displacement, shape (nodes, 3), node i + (2n+1)(j + (n+1)k) at
(i h, j h, k h). --ordering best factors with each of metis, nesdis and CHOLMOD's default (each
timed, nnz(L) reported) and keeps the fastest; metis (the default) and nesdis tie within noise at
n = 32, 40, 48 (nesdis 1-2 % less fill), CHOLMOD's default picks metis's ordering here, and amd has
1.6-1.7x the fill and 3x the factorisation time. --no-contact / --no-memory drop contact / memory
(check (1): K u = F); --check-2d also runs benches/numpy_reference.py in plane strain on the 2n x n
grid and compares (the 3D solution is z-independent with u_z = 0); --direct-history checks the
moment recursion against the O(N^2) sum. --threads sets the BLAS threads (default 1, as the 2D
peer; 2 gained about 15 % in the factorisation at n = 40 and nothing in the solves).

Install (Debian 12; its SuiteSparse 5.12 needs scikit-sparse < 0.5):
    apt-get update && apt-get install -y libsuitesparse-dev
    pip install numpy scipy "scikit-sparse<0.5"     # add --break-system-packages if pip asks
    python3 -c "import sksparse.cholmod"            # check the import
Strongly advised, a 5x faster CHOLMOD (Debian's libcholmod otherwise runs on the reference BLAS):
    apt-get install -y libopenblas0-pthread
This script then loads OpenBLAS for itself only (--blas auto, by LD_LIBRARY_PATH and one re-exec),
whatever the system's libblas.so.3 alternative points to. On a virtual machine whose processor
OpenBLAS does not recognise (it then says "core Prescott" and runs without AVX), set
OPENBLAS_CORETYPE to the processor's family (e.g. SkylakeX where /proc/cpuinfo lists avx512f):
at n = 32 the factorisation went 5.3 s -> 2.4 s (docs/method.md §9.5).
"""
import argparse
import ctypes
import math
import os
import sys
import time

T0 = time.perf_counter()


def _early_args():
    """--threads, --blas and --no-malloc-tune act before numpy and CHOLMOD load."""
    threads, blas = "1", "auto"
    for i, a in enumerate(sys.argv):
        if a.startswith("--threads"):
            threads = a.split("=", 1)[1] if "=" in a else sys.argv[i + 1]
        if a.startswith("--blas"):
            blas = a.split("=", 1)[1] if "=" in a else sys.argv[i + 1]
    return threads, blas, "--no-malloc-tune" not in sys.argv


_THREADS, _BLAS, _TUNE = _early_args()
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = _THREADS
_OPENBLAS = "/usr/lib/x86_64-linux-gnu/openblas-pthread"
if _BLAS == "auto":
    _BLAS = "openblas" if os.path.isdir(_OPENBLAS) else "system"
if _BLAS not in ("system", "openblas"):
    raise SystemExit("--blas is auto, system or openblas")
if _BLAS == "openblas" and not os.path.isdir(_OPENBLAS):
    raise SystemExit(f"--blas openblas: {_OPENBLAS} missing (apt-get install libopenblas0-pthread)")
_ENV = {}
if _BLAS == "openblas":
    # Debian's libcholmod loads libblas.so.3 / liblapack.so.3: point the loader at OpenBLAS's for
    # this process only (the system alternative is left as it is)
    _ENV["LD_LIBRARY_PATH"] = _OPENBLAS + ":" + os.environ.get("LD_LIBRARY_PATH", "")
if _TUNE:
    # glibc keeps freed big blocks instead of unmapping them: fewer first-touch page faults, which
    # are slow on this (virtual) machine; about 1 s of 6 at n = 32
    _ENV.update(MALLOC_MMAP_THRESHOLD_="4294967296", MALLOC_TRIM_THRESHOLD_="68719476736")
_MARK = f"{_BLAS},{_TUNE}"
if _ENV and os.environ.get("_NUMPY_REF3D_ENV") not in (_MARK, "set"):      # re-execute once
    os.environ.update(_ENV, _NUMPY_REF3D_ENV=_MARK)
    os.execv(sys.executable, [sys.executable] + sys.argv)
os.environ["_NUMPY_REF3D_ENV"] = "set"       # children (the --check-2d peer) inherit, no loop

try:
    import resource

    import numpy as np
    import scipy.linalg as sla
    import scipy.sparse as sp
    from sksparse.cholmod import analyze, cholesky
except ImportError as e:  # pragma: no cover
    raise SystemExit(f"numpy_reference_3d.py needs numpy, scipy and scikit-sparse ({e}); see the "
                     "install lines at the top of this file")

E_MOD, NU = 1.0, 0.3
LAM, MU = E_MOD * NU / ((1 + NU) * (1 - 2 * NU)), E_MOD / (2 * (1 + NU))
LAM_B, MU_B = 0.0, 0.5                  # B0 e = e
B_COEF = [0.25, 1.0, 1.0]              # b(s) = (0.5 + s)^2 = 0.25 + s + s^2
LZ = 0.25
S_, A_, B_, ALPHA, EPS, G = 0.1, 0.04, 0.02, 100.0, 1e-8, 0.2
TOL, MAX_IT, ARMIJO, MIN_STEP = 1e-10, 200, 1e-4, 1e-14
CHUNK = 4096                           # cells per vectorised element batch
GAUSS = np.array([-1.0, 1.0]) / math.sqrt(3.0)


def mesh(n):
    """Node coordinates (node i + nx1 (j + ny1 k)) and the hexahedra (8 nodes, lexicographic
    corners: a = ax + 2 ay + 4 az with a_d in {0, 1})."""
    if n % 4:
        raise SystemExit("--n must be a multiple of 4 (n/4 cells across Lz = 0.25)")
    nx, ny, nz = 2 * n, n, n // 4
    h = 1.0 / n
    ii, jj, kk = np.meshgrid(np.arange(nx + 1), np.arange(ny + 1), np.arange(nz + 1), indexing="ij")
    idx = lambda i, j, k: i + (nx + 1) * (j + (ny + 1) * k)
    pts = np.empty(((nx + 1) * (ny + 1) * (nz + 1), 3))
    node = idx(ii, jj, kk).ravel()
    pts[node] = np.column_stack([ii.ravel() * h, jj.ravel() * h, kk.ravel() * h])
    ci, cj, ck = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij"))
    corners = [(ax, ay, az) for az in (0, 1) for ay in (0, 1) for ax in (0, 1)]
    cells = np.column_stack([idx(ci + ax, cj + ay, ck + az) for ax, ay, az in corners])
    return pts, cells, (nx, ny, nz), np.array(corners, float) * 2 - 1


def element_matrices(pts, cells, ref):
    """K_A and K_B element matrices for every cell at once, dofs 3a + i: (cells, 24, 24)."""
    q = np.array([(x, y, z) for z in GAUSS for y in GAUSS for x in GAUSS])          # (8, 3), weights 1
    # trilinear N_a(xi) = prod_d (1 + ref_ad xi_d)/8 and its reference gradient (8 q, 8 a, 3)
    f = 1 + q[:, None, :] * ref[None, :, :]                                           # (q, a, d)
    dn = np.empty((8, 8, 3))
    for d in range(3):
        others = [e for e in range(3) if e != d]
        dn[:, :, d] = ref[None, :, d] * f[:, :, others[0]] * f[:, :, others[1]] / 8
    xe = pts[cells]                                                                   # (e, a, 3)
    jac = np.einsum("qar,ead->eqrd", dn, xe)                                          # dX_d/dxi_r
    det = np.linalg.det(jac)
    if (det <= 0).any():
        raise RuntimeError("inverted cell")
    grad = np.linalg.solve(jac, np.broadcast_to(dn.transpose(0, 2, 1), jac.shape[:2] + (3, 8)))
    grad = grad.transpose(0, 1, 3, 2)                                                 # (e, q, a, i) = dN_a/dx_i
    # K[a i, b j] = sum_q det (lam g_ai g_bj + mu (g_aj g_bi + delta_ij g_a . g_b)), from the one
    # batched product O[(a i), (b j)] = sum_q det g_ai g_bj, (24 x 8)(8 x 24) per cell
    ne = len(cells)
    gq = grad.reshape(ne, 8, 24)
    outer = np.matmul((gq * det[:, :, None]).transpose(0, 2, 1), gq).reshape(ne, 8, 3, 8, 3)
    dot = np.einsum("eaibi->eab", outer)                                              # g_a . g_b
    sym = outer.transpose(0, 1, 4, 3, 2) + dot[:, :, None, :, None] * np.eye(3)[None, None, :, None, :]
    mats = [(LAM * outer + MU * sym).reshape(ne, 24, 24), (MU_B * sym).reshape(ne, 24, 24)]
    assert LAM_B == 0.0
    return mats


def face_quadrature(pts, quads):
    """2x2 Gauss on planar axis-aligned quads (4 nodes, counter-clockwise): points (f, 4, 3),
    weights (f, 4) and shape values (4 q, 4 a)."""
    s = np.array([(x, y) for y in GAUSS for x in GAUSS])
    ref = np.array([(-1, -1), (1, -1), (1, 1), (-1, 1)], float)
    shape = (1 + s[:, None, 0] * ref[None, :, 0]) * (1 + s[:, None, 1] * ref[None, :, 1]) / 4
    xf = pts[quads]
    xq = np.einsum("qa,fad->fqd", shape, xf)
    e1, e2 = xf[:, 1] - xf[:, 0], xf[:, 3] - xf[:, 0]
    area = np.linalg.norm(np.cross(e1, e2), axis=1)
    return xq, np.repeat(area[:, None] / 4, 4, axis=1), shape


class Law:
    """j(r) = S phi(rho(r)), rho = sqrt(r^2+eps^2) - eps, phi(s) = b s + (a-b)(1-e^{-alpha s})/alpha;
    returns j, j', j''."""
    @staticmethod
    def eval(r):
        root = np.hypot(r, EPS)
        s, ds, dds = r * r / (root + EPS), r / root, EPS * EPS / root**3
        ex = np.exp(-ALPHA * s)
        phi = B_ * s - (A_ - B_) * np.expm1(-ALPHA * s) / ALPHA
        mu, dmu = (A_ - B_) * ex + B_, -ALPHA * (A_ - B_) * ex
        return S_ * phi, S_ * mu * ds, S_ * (dmu * ds * ds + mu * dds)


def contact_solve(q, w, d, r, stats):
    """argmin 1/2 (r-d)'Q(r-d) + sum w j(r) s.t. r <= g by projected Newton; returns r, iterations."""
    cq = np.diag(q).copy()
    r = np.minimum(r, G)
    scale = max(np.abs(q @ d).max(), S_ * max(A_, B_) * w.max(), 1e-300)
    cache = {}
    its = 0
    while True:
        j0, j1, j2 = Law.eval(r)
        grad = q @ (r - d) + w * j1
        res = np.abs(np.minimum(cq * (G - r), -grad)).max() / scale
        if res <= TOL:
            return r, its
        if its == MAX_IT:
            raise RuntimeError(f"contact: no convergence in {MAX_IT} iterations (residual {res:.2e})")
        its += 1
        # Bertsekas' active set: at (or within delta of) the bound, pushed outwards
        delta = min(np.abs(r - np.minimum(r - grad / cq, G)).max(), 1e-3 * G)
        act = (G - r <= delta) & (grad < 0)
        fr = ~act
        p = np.where(act, grad / cq, 0.0)
        if fr.any():
            curv = np.maximum(w[fr] * j2[fr], 0.0)
            key = (fr.tobytes(), curv.tobytes())
            if key not in cache:
                cache.clear()
                cache[key] = sla.cho_factor(q[np.ix_(fr, fr)] + np.diag(curv), lower=True)
                stats["factorisations"] += 1
            p[fr] = sla.cho_solve(cache[key], grad[fr])
        alpha = 1.0
        while True:                                   # Armijo along the projection arc
            trial = np.minimum(r - alpha * p, G)
            kink = fr & (np.abs(r) > EPS) & (trial * r < 0)   # do not jump over the kink r = 0
            trial[kink] = 0.0
            step = trial - r
            slope = grad @ step
            if slope < 0:
                small = np.abs(step) <= 1e-4 * np.maximum(np.abs(r), EPS)
                jt = Law.eval(trial)[0]
                rest = np.where(small, 0.5 * j2 * step**2, jt - j0 - j1 * step)
                change = slope + 0.5 * step @ (q @ step) + w @ rest
                if change <= ARMIJO * slope:
                    break
            elif not step.any():
                break
            alpha *= 0.5
            stats["cuts"] += 1
            if alpha < MIN_STEP:
                if res <= 100 * TOL:
                    return r, its
                raise RuntimeError(f"contact: line search failed (residual {res:.2e})")
        r = trial


class _CholmodFactor(ctypes.Structure):
    """cholmod_factor of SuiteSparse 5.x (cholmod_core.h), to read the supernodes in place."""
    _fields_ = ([(f, ctypes.c_size_t) for f in ("n", "minor")]
                + [(f, ctypes.c_void_p) for f in ("Perm", "ColCount", "IPerm")] + [("nzmax", ctypes.c_size_t)]
                + [(f, ctypes.c_void_p) for f in ("p", "i", "x", "z", "nz", "next", "prev")]
                + [(f, ctypes.c_size_t) for f in ("nsuper", "ssize", "xsize", "maxcsize", "maxesize")]
                + [(f, ctypes.c_void_p) for f in ("super", "pi", "px", "s")]
                + [(f, ctypes.c_int) for f in ("ordering", "is_ll", "is_super", "is_monotonic", "itype",
                                                "xtype", "dtype", "useGPU")])


def _factor_struct(fac, n):
    """The cholmod_factor behind a sksparse Factor (the pointer stored right after its _common
    attribute in the Cython object), if it is the real double supernodal LL' of size n; else None."""
    words = (ctypes.c_void_p * 6).from_address(id(fac))
    for k in range(2, 5):
        if words[k] == id(fac._common) and words[k + 1]:
            st = _CholmodFactor.from_address(words[k + 1])
            if (st.n, st.is_super, st.is_ll, st.xtype, st.dtype) == (n, 1, 1, 1, 0) and st.itype in (0, 2):
                return st
    return None


def trailing_block(fac, n, m):
    """(L_cc, nnz(L)) read in place from CHOLMOD's supernodal factor: supernode k holds columns
    super[k]..super[k+1]-1, rows s[pi[k]:pi[k+1]], values x[px[k]:] column-major. None if the
    layout is not the expected one."""
    st = _factor_struct(fac, n)
    if st is None:
        return None
    ity, cty = (np.int32, ctypes.c_int32) if st.itype == 0 else (np.int64, ctypes.c_int64)
    view = lambda ptr, ct, count, dt: np.frombuffer((ct * count).from_address(ptr), dtype=dt)
    ns = st.nsuper
    sup, pi, px = (view(p, cty, ns + 1, ity).astype(np.int64) for p in (st.super, st.pi, st.px))
    srow = view(st.s, cty, st.ssize, ity)
    xval = view(st.x, ctypes.c_double, st.xsize, np.float64)
    ncol, nrow = np.diff(sup), np.diff(pi)
    nnz = int(np.sum(ncol * (ncol + 1) // 2 + ncol * (nrow - ncol)))   # as L() would count
    c0 = n - m
    l_cc = np.zeros((m, m))
    for k in np.flatnonzero(sup[1:] > c0):
        rows = srow[pi[k]:pi[k + 1]]
        k0, k1 = sup[k], sup[k + 1]
        block = xval[px[k]:px[k] + len(rows) * (k1 - k0)].reshape(k1 - k0, len(rows))  # [col, row]
        cols, sel = np.arange(max(k0, c0), k1), rows >= c0
        l_cc[np.ix_(rows[sel] - c0, cols - c0)] = block[cols - k0][:, sel].T
    return np.tril(l_cc), nnz


def factor_contact_last(kmat, cdof, ordering, copy_l=False):
    """CHOLMOD LL' of K with the contact unknowns last: (factor, permutation, L_cc, timings)."""
    n, m = kmat.shape[0], len(cdof)
    t0 = time.perf_counter()
    inner = np.setdiff1d(np.arange(n), cdof)
    k_ii = kmat[inner][:, inner].tocsc()
    perm_ii = analyze(k_ii, mode="supernodal", ordering_method=ordering).P()
    del k_ii
    perm = np.concatenate([inner[perm_ii], cdof])
    kp = kmat[perm][:, perm].tocsc()
    kp.sort_indices()
    t1 = time.perf_counter()
    fac = cholesky(kp, mode="supernodal", ordering_method="natural")
    t2 = time.perf_counter()
    del kp
    if not np.array_equal(fac.P(), np.arange(n)):
        raise RuntimeError("CHOLMOD permuted the natural ordering")
    got = None if copy_l else trailing_block(fac, n, m)
    if got is None:                   # sksparse's L(): a simplicial sparse copy of the whole factor
        if not copy_l:
            print("  (CHOLMOD's factor layout not recognised: reading L_cc from L())")
        lower = fac.L()
        at = lower.indptr[n - m]
        l_cc = np.zeros((m, m))
        l_cc[lower.indices[at:] - (n - m), np.repeat(np.arange(m), np.diff(lower.indptr[n - m:]))] = lower.data[at:]
        got = l_cc, lower.nnz
        del lower
    l_cc, nnz = got
    t3 = time.perf_counter()
    return fac, perm, l_cc, nnz, {"ordering": t1 - t0, "factorisation": t2 - t1, "condensation": t3 - t2}


def drop_last(mat):
    """The leading (n-1) x (n-1) block of a CSC matrix with sorted indices."""
    mat.sort_indices()
    n = mat.shape[0] - 1
    end = mat.indptr[n]
    keep = mat.indices[:end] < n
    counts = np.add.reduceat(keep, mat.indptr[:n]) if end else np.zeros(n, int)
    counts[np.diff(mat.indptr[:n + 1]) == 0] = 0
    indptr = np.concatenate([[0], np.cumsum(counts)]).astype(mat.indptr.dtype)
    return sp.csc_matrix((mat.data[:end][keep], mat.indices[:end][keep], indptr), shape=(n, n))


def assemble(n_cells):
    """K_A, K_B (CSC, free unknowns), the load profile f_hat (F(t) = (1-e^{-2t}) f_hat), the
    contact unknowns (u_y of the contact nodes), their weights, the dof map and the mesh."""
    pts, cells, (nx, ny, nz), ref = mesh(n_cells)
    h = 1.0 / n_cells
    n_nodes = len(pts)
    x, y, z = pts.T
    tiny = 1e-9 * h
    fixed = np.zeros((n_nodes, 3), bool)
    fixed[x < tiny] = True                                          # x = 0 clamped
    fixed[(z < tiny) | (z > LZ - tiny), 2] = True                   # u_z = 0 on both z faces
    free = np.full(3 * n_nodes, -1, np.int64)
    free[~fixed.ravel()] = np.arange((~fixed).sum())
    n = int((~fixed).sum())
    # coo -> csc with the constrained dofs sent to a dummy index n: no masking of the 24 x 24
    # entries of every cell; the dummy row and column are cut from the csc afterwards
    edof = free[(3 * cells[:, :, None] + np.arange(3)).reshape(len(cells), 24)]
    edof = np.where(edof >= 0, edof, n).astype(np.int32)
    shape24 = (len(cells), 24, 24)
    rows = np.broadcast_to(edof[:, :, None], shape24).ravel()
    cols = np.broadcast_to(edof[:, None, :], shape24).ravel()
    data = np.empty((2,) + shape24)
    for c0 in range(0, len(cells), CHUNK):                          # bounded temporaries
        sl = slice(c0, c0 + CHUNK)
        data[0, sl], data[1, sl] = element_matrices(pts, cells[sl], ref)
    k_a, k_b = (drop_last(sp.coo_matrix((data[i].ravel(), (rows, cols)), shape=(n + 1, n + 1)).tocsc())
                for i in range(2))
    del data, rows, cols
    k_a.sort_indices()
    k_b.sort_indices()
    assert np.array_equal(k_a.indices, k_b.indices) and np.array_equal(k_a.indptr, k_b.indptr)

    # traction on y = 1: F(t) = (1 - e^{-2t}) f_hat
    fi, fk = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(nz), indexing="ij"))
    node = lambda i, j, kk: i + (nx + 1) * (j + (ny + 1) * kk)
    top = np.column_stack([node(fi, ny, fk), node(fi + 1, ny, fk), node(fi + 1, ny, fk + 1), node(fi, ny, fk + 1)])
    xq, wq, shape = face_quadrature(pts, top)
    fy = np.einsum("fq,qa->fa", -0.1 * xq[:, :, 0] * wq, shape)   # (faces, 4)
    dofs = free[3 * top + 1]
    f_hat = np.bincount(dofs[dofs >= 0], fy[dofs >= 0], minlength=n)

    # contact nodes on y = 0, x > 0: u_nu = -u_y, weights = row sums of the face mass
    bot = np.column_stack([node(fi, 0, fk), node(fi + 1, 0, fk), node(fi + 1, 0, fk + 1), node(fi, 0, fk + 1)])
    _, wq_b, shape_b = face_quadrature(pts, bot)
    wnode = np.bincount(bot.ravel(), np.einsum("fq,qa->fa", wq_b, shape_b).ravel(), minlength=n_nodes)
    cnodes = np.flatnonzero((y < tiny) & (x > tiny))
    cdof = free[3 * cnodes + 1]
    assert (cdof >= 0).all()
    w = wnode[cnodes]
    m = len(cnodes)
    return argparse.Namespace(k_a=k_a, k_b=k_b, f_hat=f_hat, cdof=cdof, w=w, free=free, pts=pts,
                              dims=(nx, ny, nz), n=n, m=m)


def blas_loaded():
    """The system BLAS mapped into this process (the one CHOLMOD calls), numpy's aside."""
    with open("/proc/self/maps") as maps:
        libs = {line.split()[-1] for line in maps if "/usr/lib/" in line
                and ("libblas" in line or "libopenblas" in line)}
    return ", ".join(sorted(libs)) or "none"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=32, help="cells per unit length (multiple of 4)")
    ap.add_argument("--steps", type=int, default=32)
    ap.add_argument("--save", help="write the final nodal displacement (nodes x 3) to this .npy")
    ap.add_argument("--ordering", default="metis", choices=["best", "amd", "metis", "nesdis", "default"])
    ap.add_argument("--lcc", default="struct", choices=["struct", "copy"],
                    help="read L_cc in place from CHOLMOD's supernodes (struct) or from sksparse's "
                    "L(), a sparse copy of the whole factor (copy)")
    ap.add_argument("--no-contact", action="store_true")
    ap.add_argument("--no-memory", action="store_true")
    ap.add_argument("--check-2d", action="store_true",
                    help="compare with benches/numpy_reference.py in plane strain")
    ap.add_argument("--direct-history", action="store_true",
                    help="also form h_n by the O(N^2) sum and report its distance to the recursion")
    ap.add_argument("--threads", default="1", help="BLAS threads (numpy's and CHOLMOD's)")
    ap.add_argument("--no-malloc-tune", action="store_true",
                    help="leave glibc's malloc thresholds alone (default: re-execute with "
                    "MALLOC_MMAP_THRESHOLD_ / MALLOC_TRIM_THRESHOLD_ raised)")
    ap.add_argument("--blas", default="auto", choices=["auto", "system", "openblas"],
                    help="CHOLMOD's BLAS: Debian's OpenBLAS if installed (auto), or the system's "
                    "libblas.so.3 alternative")
    args = ap.parse_args()
    n_cells, steps = args.n, args.steps
    k = 1.0 / steps
    bcoef = np.zeros(3) if args.no_memory else np.array(B_COEF)
    times = {"import": time.perf_counter() - T0}

    # ---- assembly --------------------------------------------------------------------------
    tic = time.perf_counter()
    a = assemble(n_cells)
    k_a, k_b, f_hat, cdof, w, free, pts = a.k_a, a.k_b, a.f_hat, a.cdof, a.w, a.free, a.pts
    (nx, ny, nz), n, m, n_nodes = a.dims, a.n, a.m, len(a.pts)
    c0 = 0.5 * k * bcoef[0]
    kmat = sp.csc_matrix((k_a.data + c0 * k_b.data, k_a.indices, k_a.indptr), shape=(n, n))
    load = lambda t: (1 - math.exp(-2 * t)) * f_hat
    times["assembly"] = time.perf_counter() - tic
    print(f"numpy reference 3D: n = {n_cells} ({nx}x{ny}x{nz} Q1 hexahedra), {n} unknowns, "
          f"{m} contact nodes, {steps} steps, contact {'off' if args.no_contact else 'on'}, "
          f"memory {'off' if args.no_memory else 'on'}; CHOLMOD's BLAS {blas_loaded()}, "
          f"{_THREADS} thread(s), malloc tuned {'no' if args.no_malloc_tune else 'yes'}", flush=True)

    # ---- factorisation with the contact unknowns last -----------------------------------------
    methods = ["metis", "nesdis", "default"] if args.ordering == "best" else [args.ordering]
    best = None
    for method in methods:
        got = factor_contact_last(kmat, cdof, method, args.lcc == "copy")
        print(f"  ordering {method:7s} (on K_ii, contact last): nnz(L) {got[3]}, ordering "
              f"{got[4]['ordering']:.3f} s, factorisation {got[4]['factorisation']:.3f} s, "
              f"L_cc {got[4]['condensation']:.3f} s", flush=True)
        if best is None or got[4]["factorisation"] < best[1][4]["factorisation"]:
            best = (method, got)
        del got
    method, (fac, perm, l_cc, nnz_l, tf) = best
    times.update(tf)
    tic = time.perf_counter()
    q = l_cc @ l_cc.T                                               # Q = S = W^-1
    q = 0.5 * (q + q.T)
    times["condensation"] += time.perf_counter() - tic

    # ---- time steps --------------------------------------------------------------------------
    tic = time.perf_counter()
    stats = {"cuts": 0, "factorisations": 0}
    moments = np.zeros((3, n))                                      # M_j = sum w_i (t_n - t_i)^j u_i
    r = np.zeros(m)
    u = np.zeros(n)
    lam = np.zeros(m)
    iters = []
    rhs = np.zeros(n)
    past, hist_err = [], 0.0

    def solve_step(b, r):
        """u with K u + C'lam = b, C u = r from the contact problem; one forward + one backward."""
        yv = fac.solve_L(b[perm], use_LDLt_decomposition=False)
        uc_free = sla.solve_triangular(l_cc, yv[n - m:], trans="T", lower=True)
        d = -uc_free                                                # C u_free
        its = 0
        if args.no_contact:
            r = d.copy()
        else:
            r, its = contact_solve(q, w, d, r, stats)
        yv[n - m:] = l_cc.T @ (-r)
        up = fac.solve_Lt(yv, use_LDLt_decomposition=False)
        uu = np.empty(n)
        uu[perm] = up
        return uu, r, q @ (d - r), its

    if np.any(load(0.0) != 0):
        raise NotImplementedError("F_0 != 0 would need K_A factored for step 0")
    # step 0: K_A u_0 + C'lam = F_0 = 0, and j'(0) = 0: u_0 = 0, r = 0
    iters.append(0)
    for step in range(steps + 1):
        if step > 0:
            hist = k * (bcoef @ moments)
            if args.direct_history:                                # h_n = k sum w_i b(t_n - t_i) u_i
                direct = sum((0.5 if i == 0 else 1.0) * np.polyval(bcoef[::-1], (step - i) * k) * ui
                             for i, ui in enumerate(past)) * k
                hist_err = max(hist_err, np.abs(direct - hist).max() / max(np.abs(direct).max(), 1e-300))
            rhs = load(step * k) - k_b @ hist
            u, r, lam, it = solve_step(rhs, r)
            iters.append(it)
        moments[0] += (0.5 if step == 0 else 1.0) * u              # push u_n with omega_n
        if args.direct_history:
            past.append(u.copy())
        for j in range(2, 0, -1):                                  # shift t_n -> t_{n+1}
            for l_ in range(j):
                moments[j] += math.comb(j, l_) * k ** (j - l_) * moments[l_]
    times["steps"] = time.perf_counter() - tic
    times["total"] = time.perf_counter() - T0
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

    print(f"CHOLMOD supernodal LL', ordering {method} on K_ii + contact last: nnz(L) {nnz_l}")
    phases = ["import", "assembly", "ordering", "factorisation", "condensation", "steps", "total"]
    print("time [s]: " + ", ".join(f"{key} {times[key]:.3f}" for key in phases))
    print(f"peak RSS {rss:.0f} MiB; Newton iterations {sum(iters)} in all (max {max(iters)} per step), "
          f"line-search cuts {stats['cuts']}, dense Hessian factorisations {stats['factorisations']}")

    # ---- checks at T ----------------------------------------------------------------------------
    cu = np.zeros(n)
    cu[cdof] = -lam                                                 # C'lam
    resid = kmat @ u + cu - rhs
    print(f"at T: ||K u + C'lam - (F - K_B h)|| / ||F|| = {np.linalg.norm(resid) / np.linalg.norm(load(1.0)):.2e}")
    if args.no_memory:
        print(f"  (no memory: K = K_A, so this is ||K_A u - F|| / ||F||{' with lam = 0' if args.no_contact else ''})")
    if args.direct_history:
        print(f"  history: max_n |h_n(recursion) - h_n(direct sum)| / max|h_n| = {hist_err:.2e}")
    if not args.no_contact:
        j1 = Law.eval(r)[1]
        on = r >= G
        bound_force = lam - w * j1                                  # multiplier of r <= g
        lscale = np.abs(lam).max()
        print(f"  max u_nu {r.max():.6f} (g = {G}), {int(on.sum())} of {m} nodes on the bound")
        print(f"  KKT: max(u_nu - g) {np.max(r - G):.2e}, min bound force {bound_force.min():.2e} "
              f"(on the bound {bound_force[on].min() if on.any() else float('nan'):.2e}), "
              f"max |(g - u_nu) * bound force| {np.abs((G - r) * bound_force).max():.2e}, "
              f"law off the bound max |lam - w j'| / max|lam| "
              f"{np.abs(bound_force[~on]).max() / lscale if (~on).any() else 0:.2e}")
    nodal = np.zeros(3 * n_nodes)
    nodal[free >= 0] = u
    nodal = nodal.reshape(n_nodes, 3)
    grid = nodal.reshape(nz + 1, ny + 1, nx + 1, 3)
    umax = np.abs(nodal).max()
    zdev = np.abs(grid[:, :, :, :2] - grid[:1, :, :, :2]).max()
    print(f"  plane strain: max|u| {umax:.6e}, max|u_z| / max|u| {np.abs(nodal[:, 2]).max() / umax:.2e}, "
          f"max_k |u_xy(.,.,z_k) - u_xy(.,.,0)| / max|u| {zdev / umax:.2e}")
    if args.save:
        np.save(args.save, nodal)
    if args.check_2d:
        check_2d(args, grid, umax)


def check_2d(args, grid, umax):
    """The 2D peer (plane stress code) with E' = E/(1-nu^2), nu' = nu/(1-nu) is plane strain."""
    import importlib.util
    import tempfile
    spec = importlib.util.spec_from_file_location(
        "numpy_reference", os.path.join(os.path.dirname(os.path.abspath(__file__)), "numpy_reference.py"))
    ref2d = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ref2d)
    ref2d.E, ref2d.NU = E_MOD / (1 - NU**2), NU / (1 - NU)
    if args.no_memory:
        ref2d.B_COEF = [0.0, 0.0, 0.0]
    if args.no_contact:
        raise SystemExit("--check-2d needs contact on (the 2D peer has no switch)")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "u2d.npz")
        argv = sys.argv
        sys.argv = ["numpy_reference.py", "--nx", str(2 * args.n), "--ny", str(args.n),
                    "--steps", str(args.steps), "--out", out]
        try:
            ref2d.main()
        finally:
            sys.argv = argv
        u2d = np.load(out)["u"].reshape(args.n + 1, 2 * args.n + 1, 2)
    diff = np.abs(grid[:, :, :, :2] - u2d[None]).max() / umax
    print(f"  vs the 2D peer in plane strain: max|u_3d - u_2d| / max|u| = {diff:.2e}")


if __name__ == "__main__":
    main()
