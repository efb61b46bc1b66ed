"""Where a default solve spends its time, and how it compares with the solver before issue 9,
with scikit-fem, and in dataset generation and time stepping.

    python bench/fem/solver.py                               # this tree only
    python bench/fem/solver.py --baseline ../i9-base         # side by side with a checkout
    python bench/fem/solver.py --baseline ../i9-base --skip-generate --repeat 9

Sections (medians over ``--repeat`` runs; ratios are the reliable part on a shared machine):

1. Stage table of the default forearm harmonic solve (examples/forearm.toml: mode 1, Q9,
   PML side), from ``fem.solve.solve_mode(..., stages=...)``.
2. The same solve (``fem.simulate``, end to end) in this tree and in ``--baseline`` (another
   checkout of the repository, e.g. a git worktree of the revision before issue 9), each in its
   own fresh process, alternating rounds; prints both medians and the speed-up.
3. Peer: the same forearm mesh (order 2, 0.5 / 2 mm, mode 0, static, real moduli, fixed side
   and base) solved with scikit-fem (``pip install hapticrom[bench]``) against ``fem.simulate``.
   scikit-fem assembles plain full-integration axisymmetric elasticity and solves with its
   default ``skfem.solve`` (scipy's sparse direct solver); skipped with a message if absent.
4. Dataset generation rate (samples/min) of the default space on 1 and 2 workers through
   ``surrogate.data.generate.generate`` (``--gen-n`` samples per run).
5. Transient per-step cost of examples/unit-transient.toml (generalised-alpha, one
   factorisation): (t(N steps) - t(1 step)) / (N - 1), this tree and ``--baseline``.

No assertions: numbers go into the README and the issue note.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FOREARM = ROOT / "examples" / "forearm.toml"
TRANSIENT = ROOT / "examples" / "unit-transient.toml"
SPACE = ROOT / "datasets" / "spaces" / "default.toml"


# ---------------------------------------------------------------- child (runs in either tree)
def _child(kind: str, reps: int, steps: int) -> dict:
    """Timings (s) measured inside a fresh process whose ``fem`` is the tree under test. Only
    APIs present before and after issue 9 are used."""
    import numpy as np

    from fem import simulate
    from fem.assembly import assemble_vector
    from fem.scene import load_scene

    if kind == "harmonic":
        scene = load_scene(FOREARM)
        simulate(scene)  # warm-up: imports, first-touch allocations
        times = []
        for _ in range(reps):
            t0 = time.perf_counter()
            simulate(scene)
            times.append(time.perf_counter() - t0)
        return {"times": times}
    if kind == "transient":
        from fem.problem import build_problem, drive_omega
        from fem.solve import OperatorLog
        from fem.transient import solve_transient
        from fem.transient_analysis import load_history, system_matrices

        scene = load_scene(TRANSIENT)
        problem = build_problem(scene)
        dm, K, M, C = system_matrices(problem, drive_omega(scene), OperatorLog())
        history, k = load_history(scene, problem)
        f = np.repeat(assemble_vector(dm, problem.load)[:, None], k, axis=1)
        dt = scene.analysis.time_step_s

        def run(n: int) -> float:
            t0 = time.perf_counter()
            solve_transient(M, K, f, history, dt, n, C=C, rho_inf=scene.analysis.rho_inf,
                            record_dofs=np.arange(10))
            return time.perf_counter() - t0

        run(2)
        one = [run(1) for _ in range(reps)]
        many = [run(steps) for _ in range(reps)]
        return {"one": one, "many": many, "steps": steps, "dofs": int(dm.n_free)}
    raise ValueError(f"unknown child kind {kind!r}")


def _in_tree(tree: Path, kind: str, reps: int, steps: int = 0, solver: str = "") -> dict:
    """Run :func:`_child` in a fresh interpreter whose imports resolve to ``tree``;
    ``solver`` forces a backend of this tree (``HAPTICROM_SOLVER``), "" = its default."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    env.pop("HAPTICROM_SOLVER", None)
    if solver:
        env["HAPTICROM_SOLVER"] = solver
    code = (f"import json, sys; sys.path.insert(0, {str(ROOT / 'bench' / 'fem')!r}); "
            f"import solver as b; "
            f"print(json.dumps(b._child({kind!r}, {reps}, {steps})))")
    out = subprocess.run([sys.executable, "-c", code], cwd=tree, env=env, check=True,
                         capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _ms(x: float) -> str:
    return f"{1e3 * x:8.1f}"


# ---------------------------------------------------------------- 1. stage table
def stage_table(repeat: int) -> None:
    from fem.problem import build_problem
    from fem.scene import load_scene
    from fem.solve import OperatorLog, solve_mode

    scene = load_scene(FOREARM)
    runs = []
    for _ in range(repeat + 1):
        st: dict[str, float] = {}
        t0 = time.perf_counter()
        pb = build_problem(scene)
        st["mesh, domain, load"] = time.perf_counter() - t0
        sol = solve_mode(pb.domain, pb.mode, pb.load, pb.omega, OperatorLog(), extra=pb.extra,
                         stages=st)
        st["total"] = time.perf_counter() - t0
        runs.append(st)
    runs = runs[1:]  # the first run pays imports and first-touch allocations
    print(f"## 1. stages of the default forearm harmonic solve ({sol.n_dofs} unknowns, "
          f"median of {repeat})")
    for name in runs[0]:
        print(f"  {name:<22} {_ms(statistics.median(r[name] for r in runs))} ms")


# ---------------------------------------------------------------- 2. side by side
def _variants(baseline: Path | None) -> list[tuple[str, Path, str]]:
    """(label, tree, forced solver) of every run: this tree with its default backend, with
    SuperLU alone (what a machine without the mkl extra runs) when MKL is installed, and the
    baseline checkout."""
    from fem import linalg

    runs = [("this tree", ROOT, "")]
    if linalg.default_backend() != "superlu":
        runs.append(("superlu", ROOT, "superlu"))
    return runs + ([("baseline", baseline, "")] if baseline else [])


def side_by_side(baseline: Path | None, repeat: int) -> None:
    from fem import linalg

    print("## 2. default forearm harmonic solve (fem.simulate), fresh processes, alternating; "
          f"this tree's backend: {linalg.default_backend()}")
    if baseline is None:
        print("  baseline skipped: pass --baseline PATH (a checkout of the earlier revision)")
    runs = _variants(baseline)
    times: dict[str, list[float]] = {label: [] for label, _, _ in runs}
    for _ in range(max(1, repeat // 3)):
        for label, tree, solver in runs:
            times[label] += _in_tree(tree, "harmonic", 3, solver=solver)["times"]
    med = {label: statistics.median(t) for label, t in times.items()}
    for label, _, _ in runs:
        ratio = f"  {med['baseline'] / med[label]:.2f}x faster than baseline" if (
            baseline and label != "baseline") else ""
        print(f"  {label:<9} {_ms(med[label])} ms ({len(times[label])} runs){ratio}")


# ---------------------------------------------------------------- 3. scikit-fem peer
def peer_scene():
    from fem.scene import load_scene, scene_from_dict, scene_to_dict

    d = scene_to_dict(load_scene(FOREARM))
    d["tissue"].update(side="fixed", base="fixed")
    for layer in d["tissue"]["layer"]:
        layer["loss_factor"] = 0.0
    d["load"]["direction"] = "normal"
    d["analysis"]["kind"] = "static"
    return scene_from_dict(d)


def skfem_solve(mesh_r, mesh_z, mu, lam, patch_r: float, pressure: float):
    """Static axisymmetric (mode 0) elasticity on the tensor grid with scikit-fem: Q2
    displacements, full integration, u = 0 on the side and the base, u_r = 0 on the axis, a
    normal pressure (Pa) on the skin for r < patch_r. Returns (u_z at r = z = 0 in m,
    unknowns)."""
    import numpy as np
    import skfem

    m = skfem.MeshQuad.init_tensor(mesh_r, mesh_z)
    e = skfem.ElementVector(skfem.ElementQuad2())
    basis = skfem.Basis(m, e, intorder=4)
    b0 = basis.with_element(skfem.ElementQuad0())
    mu_q, lam_q = b0.interpolate(mu), b0.interpolate(lam)

    @skfem.BilinearForm
    def stiffness(u, v, w):
        r = w.x[0]

        def strain(s):
            return [s.grad[0][0], s.grad[1][1], s[0] / r, s.grad[0][1] + s.grad[1][0]]

        eu, ev = strain(u), strain(v)
        tr_u, tr_v = eu[0] + eu[1] + eu[2], ev[0] + ev[1] + ev[2]
        inner = eu[0] * ev[0] + eu[1] * ev[1] + eu[2] * ev[2] + 0.5 * eu[3] * ev[3]
        return 2 * np.pi * r * (w.lam * tr_u * tr_v + 2 * w.mu * inner)

    top = m.facets_satisfying(lambda x: (x[1] < 1e-12) & (x[0] < patch_r + 1e-12))
    fb = skfem.FacetBasis(m, e, facets=top, intorder=4)

    @skfem.LinearForm
    def traction(v, w):
        return 2 * np.pi * w.x[0] * pressure * v[1]

    A = stiffness.assemble(basis, mu=mu_q, lam=lam_q)
    f = traction.assemble(fb)
    fixed = basis.get_dofs(lambda x: (x[0] > mesh_r[-1] - 1e-12) | (x[1] > mesh_z[-1] - 1e-12))
    axis = basis.get_dofs(lambda x: x[0] < 1e-12).nodal["u^1"]
    D = np.concatenate([fixed.flatten(), axis])
    u = skfem.solve(*skfem.condense(A, f, D=D))
    centre = int(np.argmin(m.p[0] ** 2 + m.p[1] ** 2))
    return float(u[basis.nodal_dofs[1, centre]]), A.shape[0] - np.unique(D).size


def peer(repeat: int) -> None:
    import numpy as np

    print("## 3. peer: the same forearm mesh (Q2, mode 0, static, fixed side and base)")
    try:
        import skfem  # noqa: F401
    except ImportError:
        print("  scikit-fem not installed: pip install 'hapticrom[bench]'")
        return
    from fem import simulate
    from fem.problem import build_problem

    scene = peer_scene()
    pb = build_problem(scene)
    mesh = pb.domain.mesh
    if mesh.order != 2 or mesh.n_elements != (mesh.r_lines.size - 1) * (mesh.z_lines.size - 1):
        print("  skipped: the peer needs a full Q2 tensor grid")
        return
    nz, nr = mesh.z_lines.size - 1, mesh.r_lines.size - 1
    mu = pb.domain.element_property("mu").real
    kappa = pb.domain.element_property("kappa").real
    lam = kappa - 2.0 * mu / 3.0
    # hapticrom's element order is z-major (cell (ir, jz) -> jz * nr + ir); skfem's
    # init_tensor orders cells r-major (ir * nz + jz)
    order = (np.arange(nr)[:, None] + nr * np.arange(nz)[None, :]).ravel()
    simulate(scene)
    ours, peer_t = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = simulate(scene)
        ours.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        uz, n = skfem_solve(mesh.r_lines, mesh.z_lines, mu[order], lam[order],
                           scene.load.radius_m, scene.load.amplitude_Pa)
        peer_t.append(time.perf_counter() - t0)
    m_ours, m_peer = statistics.median(ours), statistics.median(peer_t)
    print(f"  hapticrom {res.meta['dofs']} unknowns: {_ms(m_ours)} ms   scikit-fem {n} unknowns:"
          f" {_ms(m_peer)} ms   ratio {m_peer / m_ours:.2f}x  (median of {repeat})")
    ours_uz = float(np.real(res.U[list(res.r_mm).index(0.0), 1]))
    print(f"  same problem check: centre u_z hapticrom {ours_uz * 1e6:.3f} um, scikit-fem "
          f"{uz * 1e6:.3f} um (B-bar against full integration at nu = 0.47)")


# ---------------------------------------------------------------- 4. generation rate
def generation(n: int, workers: list[int]) -> None:
    from surrogate.data.generate import generate
    from surrogate.data.space import load_space

    space = load_space(SPACE)
    print(f"## 4. dataset generation, default space, {n} samples per run")
    for w in workers:
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            rep = generate(space, n, Path(tmp) / "ds", workers=w, progress=False)
            wall = time.perf_counter() - t0
        print(f"  {w} worker(s): {wall:6.1f} s  {60.0 * n / wall:7.1f} samples/min  "
              f"({rep.new_failed} failed)")


# ---------------------------------------------------------------- 5. transient
def transient(baseline: Path | None, repeat: int, steps: int) -> None:
    print(f"## 5. transient per-step cost (examples/unit-transient.toml, {steps} steps)")
    per = {}
    for label, tree, solver in _variants(baseline):
        r = _in_tree(tree, "transient", repeat, steps, solver=solver)
        one, many = statistics.median(r["one"]), statistics.median(r["many"])
        per[label] = (many - one) / (steps - 1)
        print(f"  {label:<9} {r['dofs']} unknowns: factor + 1 step {_ms(one)} ms, "
              f"per step {1e3 * per[label]:.2f} ms")
    if baseline is None:
        print("  baseline skipped: pass --baseline PATH")
        return
    for label in per:
        if label != "baseline":
            print(f"  per-step speed-up, {label}: {per['baseline'] / per[label]:.2f}x")


# ---------------------------------------------------------------- main
def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--baseline", type=Path, default=None,
                   help="checkout of the earlier revision to time side by side")
    p.add_argument("--repeat", type=int, default=6)
    p.add_argument("--gen-n", type=int, default=64, help="samples per generation run")
    p.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    p.add_argument("--steps", type=int, default=200, help="transient steps per timed run")
    p.add_argument("--skip-generate", action="store_true")
    p.add_argument("--only", choices=["stages", "side", "peer", "generate", "transient"])
    a = p.parse_args(argv)
    if a.baseline is not None:
        a.baseline = a.baseline.resolve()
    print(f"# hapticrom solver benchmark; {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.1f}")
    sections = {
        "stages": lambda: stage_table(a.repeat),
        "side": lambda: side_by_side(a.baseline, a.repeat),
        "peer": lambda: peer(a.repeat),
        "generate": lambda: None if a.skip_generate else generation(a.gen_n, a.workers),
        "transient": lambda: transient(a.baseline, max(3, a.repeat // 2), a.steps),
    }
    for name, fn in sections.items():
        if a.only in (None, name):
            fn()
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    sys.exit(main())
