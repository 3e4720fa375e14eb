"""Times SuiteSparse CHOLMOD (through scikit-sparse) on a MatrixMarket matrix: the reference
sparse Cholesky for benches/factor_vs_cholmod.rs. Prints one JSON line with median seconds.

    python3 benches/cholmod_time.py MATRIX.mtx [REPEATS]

Needs `pip install "scikit-sparse<0.5"` and Debian's libsuitesparse-dev."""
import json
import statistics
import sys
import time

import scipy.io
import scipy.sparse
from sksparse.cholmod import analyze

matrix = scipy.sparse.csc_matrix(scipy.io.mmread(sys.argv[1]))
repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 7
rhs = matrix @ __import__("numpy").ones(matrix.shape[0])

symbolic, numeric, solve = [], [], []
for _ in range(repeats):
    t = time.perf_counter()
    factor = analyze(matrix, mode="supernodal", ordering_method="amd")
    symbolic.append(time.perf_counter() - t)
    t = time.perf_counter()
    factor.cholesky_inplace(matrix)
    numeric.append(time.perf_counter() - t)
    t = time.perf_counter()
    x = factor(rhs)
    solve.append(time.perf_counter() - t)
print(json.dumps({
    "symbolic": statistics.median(symbolic),
    "numeric": statistics.median(numeric),
    "solve": statistics.median(solve),
    "nnz_factor": int(factor.L().nnz),
    "max_abs_error": float(abs(x - 1.0).max()),
}))
