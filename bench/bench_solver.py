"""Where the time of one solve goes, against the baseline solver and a scikit-fem peer.

    python bench/bench_solver.py                      # everything, 5 repeats
    python bench/bench_solver.py --repeat 9 --skip-generate
    python bench/bench_solver.py --baseline /path/to/old/worktree --n 32

Sections (medians over ``--repeat`` runs; ratios are the reliable part on a loaded machine):

1. Stage table of the default harmonic solve (examples/forearm.toml), measured by wrapping the
   library's own functions for the duration of the runs (nothing in the library changes):
   ``build_problem``, ``dynamic_element_matrices``, ``condense``, ``assemble_matrix``, the
   factorisation (scipy -> cvxopt conversion, UMFPACK symbolic, numeric), the solve, and the
   rest (residual check, interior recovery, surface sampling) as the remainder of ``simulate``.
2. ``fem.simulate`` of the same scene in this tree and in ``--baseline`` (another checkout of
   the project, run in a subprocess with that directory first on ``sys.path``), interleaved.
3. A scikit-fem peer (optional extra ``bench``): the real static mode-0 problem on our forearm
   mesh (fixed side and base, loss factors 0) with biquadratic Lagrange elements on our cell
   corners, the same materials, our constraints and our nodal load, solved with scipy's
   ``spsolve``; our ``solve_mode`` on the same problem with the plain ("full") volumetric
   integration of the same space, so the displacements must agree.
4. Transient cost (examples/unit-transient.toml cut to ``--steps`` steps): assembly, the
   factorisations and the per-step solve of ``fem.transient``.
5. Dataset generation rate on 1 and 2 workers: ``bench/bench_generate.py`` run as is.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import statistics
import subprocess
import sys
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
EXAMPLES = ROOT / "examples"
DEFAULT_BASELINE = Path("/work/wt/i9-base")

import fem.simulation as fsim  # noqa: E402 - after the sys.path set-up
import fem.solve as fsolve  # noqa: E402
import fem.transient as ftrans  # noqa: E402
import fem.transient_analysis as ftrana  # noqa: E402
from fem.scene import load_scene, scene_from_dict, scene_to_dict  # noqa: E402


class Stopwatch:
    """Accumulated seconds per stage name within one run."""

    def __init__(self) -> None:
        self.s: dict[str, float] = defaultdict(float)

    def wrap(self, name: str, fn: Callable) -> Callable:
        def timed(*args, **kwargs):
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                self.s[name] += time.perf_counter() - t0
        return timed


class _TimedSolve:
    """A factorisation whose ``solve`` calls are timed under ``name``."""

    def __init__(self, lu, watch: Stopwatch, name: str) -> None:
        self._lu, self._watch, self._name = lu, watch, name

    def solve(self, b):
        return self._watch.wrap(self._name, self._lu.solve)(b)


@contextlib.contextmanager
def patched(targets: list[tuple[object, str, Callable]]) -> Iterator[None]:
    """Replace module attributes for the duration of the block, then restore them."""
    saved = [(obj, name, getattr(obj, name)) for obj, name, _ in targets]
    try:
        for obj, name, new in targets:
            setattr(obj, name, new)
        yield
    finally:
        for obj, name, old in saved:
            setattr(obj, name, old)


def _median_ms(values: list[float]) -> float:
    return statistics.median(values) * 1e3


def stage_table(scene, repeat: int) -> float:
    """Print the stage table of ``simulate(scene)``; return the median total (s)."""
    from cvxopt import umfpack

    runs: list[dict[str, float]] = []
    for i in range(repeat + 1):  # the first run warms caches and imports; not counted
        w = Stopwatch()

        def factorize(A, many_solves=False, _w=w, _f=fsolve.factorize):
            return _TimedSolve(_w.wrap("factorise", _f)(A, many_solves), _w, "solve")

        targets = [
            (fsim, "build_problem", w.wrap("mesh, domain, load", fsim.build_problem)),
            (fsolve, "dynamic_element_matrices",
             w.wrap("element matrices", fsolve.dynamic_element_matrices)),
            (fsolve, "build_dofmap", w.wrap("dof map", fsolve.build_dofmap)),
            (fsolve, "condense", w.wrap("static condensation", fsolve.condense)),
            (fsolve, "assemble_matrix", w.wrap("assembly", fsolve.assemble_matrix)),
            (fsolve, "factorize", factorize),
            (umfpack, "symbolic", w.wrap("umfpack symbolic", umfpack.symbolic)),
            (umfpack, "numeric", w.wrap("umfpack numeric", umfpack.numeric)),
        ]
        with patched(targets):
            t0 = time.perf_counter()
            res = fsim.simulate(scene)
            total = time.perf_counter() - t0
        s = dict(w.s)
        s["scipy -> cvxopt conversion"] = (s.get("factorise", 0.0) - s.get("umfpack symbolic", 0)
                                           - s.get("umfpack numeric", 0.0))
        s.pop("factorise", None)
        s["residual, recovery, post-processing"] = total - sum(s.values())
        s["total (simulate)"] = total
        if i:
            runs.append(s)
    order = ["mesh, domain, load", "element matrices", "dof map", "static condensation",
             "assembly", "scipy -> cvxopt conversion", "umfpack symbolic", "umfpack numeric",
             "solve", "residual, recovery, post-processing", "total (simulate)"]
    print(f"## 1. stages of one default harmonic solve ({EXAMPLES.name}/forearm.toml, mode "
          f"{res.meta['modes'][0]}, order {scene.mesh.order}, {res.meta['dofs']} unknowns); "
          f"medians of {repeat} runs")
    print(f"{'stage':<38} {'median ms':>10}")
    for name in order:
        print(f"{name:<38} {_median_ms([r.get(name, 0.0) for r in runs]):>10.1f}")
    return statistics.median(r["total (simulate)"] for r in runs)


_SIMULATE_SNIPPET = """
import json, sys, time
sys.path.insert(0, '.')
from fem import simulate
from fem.scene import load_scene
scene = load_scene(sys.argv[1]); simulate(scene)
times = []
for _ in range(int(sys.argv[2])):
    t0 = time.perf_counter(); simulate(scene); times.append(time.perf_counter() - t0)
print(json.dumps(times))
"""


def _simulate_times(tree: Path, scene_path: Path, repeat: int) -> list[float]:
    out = subprocess.run([sys.executable, "-c", _SIMULATE_SNIPPET, str(scene_path), str(repeat)],
                         cwd=tree, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def side_by_side(baseline: Path | None, repeat: int) -> None:
    """``simulate`` of the forearm scene here and in the baseline tree, interleaved rounds."""
    print("\n## 2. fem.simulate, this tree vs the baseline (subprocesses, interleaved rounds)")
    if baseline is None or not (baseline / "fem" / "simulation.py").is_file():
        print(f"skipped: no baseline checkout at {baseline} (pass --baseline PATH)")
        return
    scene_path = EXAMPLES / "forearm.toml"
    ours: list[float] = []
    base: list[float] = []
    rounds = max(1, min(3, repeat))
    per = max(1, -(-repeat // rounds))
    for _ in range(rounds):
        ours += _simulate_times(ROOT, scene_path, per)
        base += _simulate_times(baseline, scene_path, per)
    m_ours, m_base = _median_ms(ours), _median_ms(base)
    print(f"baseline {baseline}: median {m_base:.1f} ms ({len(base)} runs)")
    print(f"this tree {ROOT}: median {m_ours:.1f} ms ({len(ours)} runs)")
    print(f"speed-up baseline / this tree: {m_base / m_ours:.2f}x")


def static_mode0_problem():
    """The real static mode-0 forearm problem: normal load, fixed side and base, no loss."""
    from fem.problem import build_problem

    d = scene_to_dict(load_scene(EXAMPLES / "forearm.toml"))
    d["tissue"].update(side="fixed", base="fixed")
    for layer in d["tissue"].get("layer", []):
        layer["loss_factor"] = 0.0
    d["load"]["direction"] = "normal"
    d["analysis"]["kind"] = "static"
    problem = build_problem(scene_from_dict(d))
    if problem.mode != 0 or problem.extra:
        raise RuntimeError("expected a plain mode-0 problem")
    return problem


def skfem_peer(repeat: int) -> None:
    """Time scikit-fem and our solver on the same real static mode-0 forearm problem."""
    print("\n## 3. peer: scikit-fem on the same forearm mesh (static, mode 0, real)")
    try:
        import skfem
    except ImportError:
        print("skipped: scikit-fem is not installed (pip install -e '.[bench]')")
        return
    from scipy.sparse.linalg import spsolve
    from skfem import (
        Basis,
        BilinearForm,
        ElementQuad2,
        ElementVector,
        MeshQuad,
        asm,
        condense,
    )

    from fem.assembly import build_dofmap

    problem = static_mode0_problem()
    domain = problem.domain
    mesh = domain.mesh
    if mesh.order != 2:
        raise RuntimeError("the peer uses biquadratic elements: the forearm mesh is order 2")
    p = mesh.order
    corners = mesh.elements[:, [0, p, (p + 1) ** 2 - 1, p * (p + 1)]]
    used, t = np.unique(corners, return_inverse=True)
    t = t.reshape(corners.shape).T
    pts = mesh.nodes[used].T
    mu_e = domain.element_property("mu").real
    lam_e = domain.element_property("kappa").real - 2.0 / 3.0 * mu_e
    dm = build_dofmap(mesh, 0, domain.fixed(), ties=domain.ties)

    @BilinearForm
    def axisymmetric_elasticity(u, v, w):
        # mode-0 strains (e_rr, e_zz, e_tt, g_rz) of (u_r, u_z) and 2 pi r dr dz (as fem does)
        r = w.x[0]
        eu = (u.grad[0][0], u.grad[1][1], u[0] / r, u.grad[0][1] + u.grad[1][0])
        ev = (v.grad[0][0], v.grad[1][1], v[0] / r, v.grad[0][1] + v.grad[1][0])
        tr_u, tr_v = eu[0] + eu[1] + eu[2], ev[0] + ev[1] + ev[2]
        energy = (w.lam * tr_u * tr_v + 2 * w.mu * (eu[0] * ev[0] + eu[1] * ev[1] + eu[2] * ev[2])
                  + w.mu * eu[3] * ev[3])
        return 2.0 * np.pi * r * energy

    def build_skfem():
        m = MeshQuad(np.ascontiguousarray(pts), np.ascontiguousarray(t))
        return m, Basis(m, ElementVector(ElementQuad2()))

    _, vb = build_skfem()
    # our full dofs (node * 2 + component) of every skfem dof, matched by coordinates
    key = {(round(r * 1e9), round(z * 1e9)): i for i, (r, z) in enumerate(mesh.nodes)}
    locs = vb.doflocs
    node_of = np.array([key[(round(r * 1e9), round(z * 1e9))] for r, z in locs.T])
    comp = np.tile([0, 1], locs.shape[1] // 2)
    if not (np.allclose(locs[:, 0::2], locs[:, 1::2]) and vb.nodal_dofs[0][0] == 0
            and vb.nodal_dofs[1][0] == 1):
        raise RuntimeError("unexpected scikit-fem vector dof layout (expected interleaved)")
    ours_dof = node_of * 2 + comp
    f_sk = problem.load[ours_dof].real
    fixed_sk = np.flatnonzero(dm.master[ours_dof] < 0)
    lam_q = lam_e[:, None] * np.ones((1, vb.X.shape[1]))
    mu_q = mu_e[:, None] * np.ones((1, vb.X.shape[1]))

    def run_skfem():
        _, basis = build_skfem()
        K = asm(axisymmetric_elasticity, basis, lam=lam_q, mu=mu_q)
        x = np.zeros(K.shape[0])
        x[basis.complement_dofs(fixed_sk)] = spsolve(*condense(K, f_sk, D=fixed_sk)[:2])
        return x

    def run_ours(volumetric):
        return fsolve.solve_mode(domain, 0, problem.load, 0.0, volumetric=volumetric)

    times: dict[str, list[float]] = defaultdict(list)
    results = {}
    for i in range(repeat + 1):
        for name, fn in (("scikit-fem (Q9 on our cells, spsolve)", run_skfem),
                         ("ours, volumetric full", lambda: run_ours("full")),
                         ("ours, volumetric bbar (default)", lambda: run_ours("bbar"))):
            t0 = time.perf_counter()
            results[name] = fn()
            if i:
                times[name].append(time.perf_counter() - t0)
    u_sk = results["scikit-fem (Q9 on our cells, spsolve)"]
    u_ours = results["ours, volumetric full"].u_full.real[ours_dof]
    diff = np.max(np.abs(u_sk - u_ours)) / np.max(np.abs(u_ours))
    print(f"scikit-fem {skfem.__version__}; {vb.N} dofs before constraints, "
          f"{mesh.n_elements} elements; max |u_skfem - u_ours(full)| / max |u| = {diff:.1e}")
    m_sk = _median_ms(times["scikit-fem (Q9 on our cells, spsolve)"])
    for name, ts in times.items():
        m = _median_ms(ts)
        print(f"{name:<40} median {m:8.1f} ms   scikit-fem / this = {m_sk / m:5.2f}x")


def transient_cost(steps: int, repeat: int) -> None:
    """Assembly, factorisation and per-step solve cost of a short unit transient."""
    print(f"\n## 4. transient ({EXAMPLES.name}/unit-transient.toml cut to {steps} steps)")
    d = scene_to_dict(load_scene(EXAMPLES / "unit-transient.toml"))
    d["analysis"]["duration_ms"] = steps * d["analysis"]["time_step_ms"]
    scene = scene_from_dict(d)
    runs = []
    for i in range(repeat + 1):
        w = Stopwatch()

        def factor(matrix, name, _w=w, _f=ftrans._factorize):
            return _TimedSolve(_w.wrap(f"factorise {name}", _f)(matrix, name), _w,
                               f"solves with {name}")

        targets = [(ftrana, "system_matrices", w.wrap("K, M, C assembly", ftrana.system_matrices)),
                   (ftrana, "solve_transient", w.wrap("solve_transient", ftrana.solve_transient)),
                   (ftrans, "_factorize", factor)]
        with patched(targets):
            t0 = time.perf_counter()
            res = fsim.simulate(scene)
            w.s["total (simulate)"] = time.perf_counter() - t0
        if i:
            runs.append(dict(w.s))
    names = sorted({k for r in runs for k in r}, key=lambda k: (k.startswith("total"), k))
    print(f"{res.meta['dofs']} unknowns, {steps} steps; medians of {repeat} runs")
    for name in names:
        print(f"{name:<45} {_median_ms([r.get(name, 0.0) for r in runs]):>10.1f} ms")
    step = statistics.median(r.get("solves with effective matrix", 0.0) for r in runs) / steps
    loop = statistics.median(r["solve_transient"] - sum(v for k, v in r.items()
                                                        if k.startswith("factorise"))
                             for r in runs) / steps
    print(f"per step: triangular solves {step * 1e3:.2f} ms, whole step (solve + products) "
          f"{loop * 1e3:.2f} ms")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="timed runs per figure (default 5)")
    ap.add_argument("--baseline", type=Path,
                    default=DEFAULT_BASELINE if DEFAULT_BASELINE.is_dir() else None,
                    help="another checkout of the project to compare simulate against")
    ap.add_argument("--steps", type=int, default=10, help="transient steps (default 10)")
    ap.add_argument("--n", type=int, default=32, help="samples per generation run (default 32)")
    ap.add_argument("--skip-generate", action="store_true", help="leave out section 5")
    args = ap.parse_args(argv)
    if args.repeat < 1 or args.steps < 1 or args.n < 1:
        ap.error("--repeat, --steps and --n must be >= 1")
    stage_table(load_scene(EXAMPLES / "forearm.toml"), args.repeat)
    side_by_side(args.baseline, args.repeat)
    skfem_peer(args.repeat)
    transient_cost(args.steps, args.repeat)
    if not args.skip_generate:
        print("\n## 5. dataset generation (bench/bench_generate.py)")
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        import bench_generate

        bench_generate.main(["--n", str(args.n), "--workers", "1", "2"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
