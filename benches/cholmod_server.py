"""SuiteSparse CHOLMOD (through scikit-sparse) as a child of benches/factor_vs_cholmod_3d.rs: it
analyses one MatrixMarket matrix with several orderings once, then refactorises on request, so
that the bench can interleave CHOLMOD's numeric factorisations with hvi's in one run.

    python3 benches/cholmod_server.py MATRIX.mtx OUTDIR default,amd,metis,nesdis,metis_last [LAST.bin]

An ordering NAME_last is the peer's (benches/numpy_reference_3d.py): CHOLMOD's ordering NAME of
K without the unknowns listed in LAST.bin (little-endian int64), those unknowns appended in their
order, and the permuted matrix analysed with the natural ordering.

Protocol (one JSON line out per line in):
  start        -> {"ready": true, "n", "nnz", "blas", "orderings": {name: {"symbolic", "perm"}}}
                  (perm: OUTDIR/perm_NAME.bin, the permutation P() as little-endian int64:
                  A[P][:, P] = L Lᵀ, i.e. entry i of the permuted order is original unknown P[i])
  factor NAME  -> {"numeric": seconds}   (Factor.cholesky_inplace on the stored analysis:
                  numeric only; the first call also allocates the factor's values)
  finish       -> {"NAME": {"nnz_L", "supernodes", "storage", "max_abs_error"}, ...}, then exits.

nnz_L is L().nnz: scikit-sparse converts the supernodal factor to a simplicial one
(cholmod_change_factor) and keeps every entry of the supernodes' lower trapezoids, the zeros
that relaxed amalgamation stored included. "storage" is Σ rows × columns over supernodes
(the square diagonal blocks in full, which is what CHOLMOD's L->xsize and faer's len_val
count), with the supernodes recovered from L()'s pattern (adjacent columns whose patterns
nest are joined, so it is an upper bound on CHOLMOD's xsize).

Needs scikit-sparse (`pip install "scikit-sparse<0.5"`) and Debian's libsuitesparse-dev."""
import ctypes
import json
import os
import sys
import time

import numpy as np
import scipy.io
import scipy.sparse
from sksparse.cholmod import analyze


def blas_in_use():
    """The BLAS libraries this process has mapped (CHOLMOD's supernodal kernels are BLAS/LAPACK)."""
    libs = set()
    with open("/proc/self/maps") as maps:
        for line in maps:
            path = line.split()[-1]
            name = os.path.basename(path)
            if name.startswith(("libblas", "libopenblas", "liblapack", "libmkl", "libblis")):
                libs.add(os.path.realpath(path))
    info = {"libraries": sorted(libs)}
    for lib in libs:
        if "openblas" in os.path.basename(lib):
            try:
                ob = ctypes.CDLL(lib)
                ob.openblas_get_corename.restype = ctypes.c_char_p
                ob.openblas_get_config.restype = ctypes.c_char_p
                info["openblas_core"] = ob.openblas_get_corename().decode()
                info["openblas_config"] = ob.openblas_get_config().decode()
                info["openblas_threads"] = ob.openblas_get_num_threads()
            except (OSError, AttributeError):
                pass
    return info


def supernodal_counts(L):
    """(number of supernodes, Σ rows × columns) of a factor converted from supernodal form."""
    L = scipy.sparse.csc_matrix(L)
    ptr, idx = L.indptr, L.indices
    lengths = np.diff(ptr)
    supernodes, storage = 0, 0
    n = L.shape[0]
    j = 0
    while j < n:
        first, nrows = j, int(lengths[j])
        while (
            j + 1 < n
            and lengths[j + 1] == lengths[j] - 1
            and np.array_equal(idx[ptr[j] + 1 : ptr[j + 1]], idx[ptr[j + 1] : ptr[j + 2]])
        ):
            j += 1
        ncols = j - first + 1
        supernodes += 1
        storage += nrows * ncols
        j += 1
    return supernodes, storage


def reply(obj):
    sys.stdout.write(json.dumps(obj) + "\n")
    sys.stdout.flush()


def main():
    path, outdir, names = sys.argv[1], sys.argv[2], sys.argv[3].split(",")
    last = np.fromfile(sys.argv[4], dtype="<i8") if len(sys.argv) > 4 else np.zeros(0, dtype="<i8")
    matrix = scipy.sparse.csc_matrix(scipy.io.mmread(path))
    rhs = matrix @ np.ones(matrix.shape[0])
    factors, orderings, matrices = {}, {}, {}
    for name in names:
        t = time.perf_counter()
        if name.endswith("_last"):
            keep = np.ones(matrix.shape[0], dtype=bool)
            keep[last] = False
            inner = np.flatnonzero(keep)
            p_inner = analyze(matrix[inner][:, inner].tocsc(), mode="supernodal", ordering_method=name[:-5]).P()
            perm = np.concatenate([inner[p_inner], last])
            permuted = matrix[perm][:, perm].tocsc()
            factor = analyze(permuted, mode="supernodal", ordering_method="natural")
            if not np.array_equal(factor.P(), np.arange(matrix.shape[0])):
                raise RuntimeError("CHOLMOD permuted the natural ordering")
            matrices[name] = (permuted, perm)
        else:
            factor = analyze(matrix, mode="supernodal", ordering_method=name)
            perm = factor.P()
            matrices[name] = (matrix, None)
        symbolic = time.perf_counter() - t
        perm_path = os.path.join(outdir, f"perm_{name}.bin")
        np.asarray(perm, dtype="<i8").tofile(perm_path)
        factors[name] = factor
        orderings[name] = {"symbolic": symbolic, "perm": perm_path}
    reply({"ready": True, "n": matrix.shape[0], "nnz": int(matrix.nnz), "blas": blas_in_use(), "orderings": orderings})
    for line in sys.stdin:
        words = line.split()
        if not words:
            continue
        if words[0] == "factor":
            factor = factors[words[1]]
            t = time.perf_counter()
            factor.cholesky_inplace(matrices[words[1]][0])
            reply({"numeric": time.perf_counter() - t})
        elif words[0] == "finish":
            out = {}
            for name in names:
                factor = factors.pop(name)
                permuted, perm = matrices.pop(name)
                error = float(abs(factor(rhs if perm is None else rhs[perm]) - 1.0).max())
                L = factor.L()  # converts the factor to simplicial form: last use of it
                del factor
                supernodes, storage = supernodal_counts(L)
                out[name] = {"nnz_L": int(L.nnz), "supernodes": supernodes, "storage": storage, "max_abs_error": error}
                del L
            reply(out)
            return
        else:
            reply({"error": f"unknown command {words[0]!r}"})


if __name__ == "__main__":
    main()
