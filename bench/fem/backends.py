"""Every installed sparse backend on the two matrices that matter, and the sparse product.

    python bench/fem/backends.py [--repeat 7]

Matrices (captured from the real solves, not synthetic):

- harmonic: the default forearm solve (examples/forearm.toml: mode 1, Q9 condensed, PML),
  complex symmetric;
- transient: the effective matrix M + gamma dt C + beta dt^2 K of examples/unit-transient.toml,
  real symmetric positive definite, solved with the two load columns of the ERM every step.

Per backend of :mod:`fem.linalg`: the first factorisation of the pattern (cold: ordering,
symbolic and numeric), a later one of the same pattern (warm: PARDISO reuses its analysis),
one solve, the factor's entries and the relative residual. Then the transient step's product
K X (X with two columns): scipy's CSR kernel against :func:`fem.linalg.product`. Medians of
``--repeat`` runs, one BLAS/MKL thread. No assertions: the numbers go into fem/linalg.py's
docstring and docs/solver-performance.md.
"""

from __future__ import annotations

import argparse
import gc
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from fem import linalg, pardiso  # noqa: E402


def harmonic_matrix() -> tuple[sp.spmatrix, np.ndarray]:
    """The default forearm system and its load, as fem.solve factors them."""
    from fem import simulate
    from fem.scene import load_scene

    captured = {}
    real_factorize = linalg.factorize

    def capture(A, *args, **kwargs):
        captured["A"] = A.copy()
        return real_factorize(A, *args, **kwargs)

    linalg.factorize = capture
    try:
        simulate(load_scene(ROOT / "examples" / "forearm.toml"))
    finally:
        linalg.factorize = real_factorize
    A = captured["A"]
    rng = np.random.default_rng(0)
    return A, rng.normal(size=A.shape[0]) + 1j * rng.normal(size=A.shape[0])


def transient_matrices() -> tuple[sp.spmatrix, sp.spmatrix, np.ndarray]:
    """(effective matrix S, stiffness K, two right-hand-side columns) of the transient example."""
    from fem.problem import build_problem, drive_omega
    from fem.scene import load_scene
    from fem.solve import OperatorLog
    from fem.transient import GeneralizedAlphaParameters, _effective_matrix
    from fem.transient_analysis import system_matrices

    scene = load_scene(ROOT / "examples" / "unit-transient.toml")
    problem = build_problem(scene)
    _, K, M, C = system_matrices(problem, drive_omega(scene), OperatorLog())
    params = GeneralizedAlphaParameters.from_rho_inf(scene.analysis.rho_inf)
    S = _effective_matrix(sp.csr_matrix(M), sp.csr_matrix(K), sp.csr_matrix(C), params,
                          scene.analysis.time_step_s)
    return S, sp.csr_matrix(K), np.random.default_rng(1).normal(size=(S.shape[0], 2))


def _median_ms(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(times)


def _entries(fac) -> str:
    if hasattr(fac, "factor_nnz"):
        return str(fac.factor_nnz)
    if hasattr(fac, "L"):
        return str(fac.L.nnz + fac.U.nnz)
    return "n/a"  # cholespy does not expose its factor


def backends(name: str, A: sp.spmatrix, b: np.ndarray, repeat: int, spd: bool | None) -> None:
    print(f"## {name}: {A.shape[0]} unknowns, {A.nnz} non-zeros, {A.dtype}, "
          f"right-hand side {b.shape}")
    print(f"  {'backend':<8} {'cold factor':>12} {'warm factor':>12} {'solve':>9} "
          f"{'entries':>10} {'residual':>9}")
    for backend in linalg.available_backends():
        if backend == "cholmod" and spd is not True:
            continue  # real SPD matrices only
        def cold(backend=backend):
            if pardiso.available():
                pardiso.clear_pool()
            linalg.factorize(A, backend, positive_definite=spd)
            gc.collect()

        def warm(backend=backend):
            linalg.factorize(A, backend, positive_definite=spd)

        t_cold = _median_ms(cold, repeat)
        warm()  # leaves the pattern's analysis in the pool
        t_warm = _median_ms(warm, repeat)
        fac = linalg.factorize(A, backend, positive_definite=spd)
        t_solve = _median_ms(lambda fac=fac: fac.solve(b), repeat)
        x = fac.solve(b)
        res = np.linalg.norm(A @ x - b) / np.linalg.norm(b)
        print(f"  {backend:<8} {t_cold:9.1f} ms {t_warm:9.1f} ms {t_solve:6.2f} ms "
              f"{_entries(fac):>10} {res:9.1e}")


def products(K: sp.spmatrix, X: np.ndarray, repeat: int) -> None:
    print(f"## product K X (transient stiffness, {K.nnz} non-zeros, X {X.shape})")
    out = np.zeros_like(X)
    print(f"  scipy CSR           {_median_ms(lambda: K @ X, repeat):6.2f} ms")
    fast = linalg.product(K, X.shape[1])
    print(f"  fem.linalg.product  {_median_ms(lambda: fast.accumulate(X, out), repeat):6.2f} ms"
          f"  ({type(fast).__module__}.{type(fast).__name__})")


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=7)
    a = p.parse_args(argv)
    print(f"# sparse backends: {', '.join(linalg.available_backends())}; {os.cpu_count()} "
          f"cores, load average {os.getloadavg()[0]:.1f}")
    with linalg.one_blas_thread():
        A, b = harmonic_matrix()
        backends("harmonic (default forearm)", A, b, a.repeat, None)
        S, K, B = transient_matrices()
        backends("transient effective matrix", S, B, a.repeat, True)
        products(K, B, a.repeat)
    return 0


if __name__ == "__main__":
    sys.exit(main())
