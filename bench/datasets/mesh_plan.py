"""One mesh topology per discrete design against each sample's own mesh: answer, size, smoothness.

    python bench/datasets/mesh_plan.py                  # 8 designs, two 40-point sweeps
    python bench/datasets/mesh_plan.py --n 4 --sweep 16 # quicker

Compares the two ``mesh_topology`` settings of a parameter space
(``surrogate.data.mesh_plan``) on the default space:

1. the plan: how long the per-design cell counts take, and how many cells they give;
2. the answer: on the first ``--n`` design points, centre and edge amplitude and the profile
   (the accuracy study's metric, ``studies.accuracy.metric``) of both meshes against a
   converged reference (quadratic elements at a third of the default sizes), with unknowns
   and solve times;
3. smoothness: the answer along a sweep of fat thickness and of frequency (one design, every
   other parameter mid-range): how many distinct meshes the sweep meets, how far the own
   mesh's answer departs from the per-design one (own/plan - 1) and how much that departure
   jumps between neighbouring points (the steps of the discretisation error a surrogate
   would have to learn), beside the physics' own change per step.

No assertions: the numbers go into docs/solver-performance.md.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

SWEEP_DESIGN = {"orientation": "forward", "attachment": "glued", "n_rings": 2}


def _spaces():
    from surrogate.data.space import load_space, space_from_dict

    own = load_space(ROOT / "datasets" / "spaces" / "default.toml")
    d = own.to_dict()
    d["space"]["mesh_topology"] = "per_design"
    return own, space_from_dict(d, check_scenes=False)


def _solve(scene, grid_mm):
    """(answer, wall time [s], unknowns) of a Scene."""
    from fem import simulate
    from studies.accuracy.metric import answer_from_result

    t0 = time.perf_counter()
    res = simulate(scene)
    return answer_from_result(res, grid_mm), time.perf_counter() - t0, int(res.meta["dofs"])


def plan_table(planned_space) -> None:
    from surrogate.data.mesh_plan import MeshPlan

    plan = MeshPlan(planned_space)
    rows = []
    t0 = time.perf_counter()
    for orientation in ("forward", "reverse"):
        for attachment in ("glued", "pogo"):
            for rings in range(4):
                row = {**planned_space.center(), "orientation": orientation,
                       "attachment": attachment, "n_rings": rings}
                r, z = plan.cells(row)
                rows.append((orientation, attachment, rings, sum(r), sum(z)))
    wall = time.perf_counter() - t0
    print(f"# plan of all {len(rows)} designs: {wall:.1f} s")
    print(f"{'design':<22} {'cells r':>7} {'cells z':>7}")
    for o, a, k, r, z in rows:
        print(f"{f'{o} {a} {k}':<22} {r:>7} {z:>7}")


def answer_table(own, planned, n: int, grid_mm) -> None:
    from fem import scene_from_dict
    from studies.accuracy.fe_ladder import REF_LEVEL, scene_at
    from studies.accuracy.metric import errors
    from surrogate.data.plan import plan_samples

    points, _ = plan_samples(own, n)
    print(f"\n# answer on the first {n} design points against quadratic FE at "
          f"{REF_LEVEL:.3g} x the default sizes (relative error, worst of centre/edge/profile)")
    print(f"{'point':>5} {'design':<20} {'own dofs':>8} {'own s':>6} {'own err':>8} "
          f"{'plan dofs':>9} {'plan s':>6} {'plan err':>8} {'plan vs own':>11}")
    cols: dict[str, list[float]] = {k: [] for k in ("od", "ot", "oe", "pd", "pt", "pe", "pvo")}
    for p in points:
        ref, _, _ = _solve(scene_from_dict(scene_at(p.scene, REF_LEVEL, 2)), grid_mm)
        a_own, t_own, d_own = _solve(own.scene(p.values), grid_mm)
        a_plan, t_plan, d_plan = _solve(planned.scene(p.values), grid_mm)
        e_own = float(errors(a_own, ref)["worst"])
        e_plan = float(errors(a_plan, ref)["worst"])
        e_pvo = float(errors(a_plan, a_own)["worst"])
        design = f"{p.values['orientation']} {p.values['attachment']} {p.values['n_rings']}"
        print(f"{p.index:>5} {design:<20} {d_own:>8} {t_own:>6.2f} {e_own:>8.2%} {d_plan:>9} "
              f"{t_plan:>6.2f} {e_plan:>8.2%} {e_pvo:>11.2%}", flush=True)
        for k, v in zip(cols, (d_own, t_own, e_own, d_plan, t_plan, e_plan, e_pvo), strict=True):
            cols[k].append(v)
    med = {k: float(np.median(v)) for k, v in cols.items()}
    print(f"{'median':>5} {'':<20} {med['od']:>8.0f} {med['ot']:>6.2f} {med['oe']:>8.2%} "
          f"{med['pd']:>9.0f} {med['pt']:>6.2f} {med['pe']:>8.2%} {med['pvo']:>11.2%}")
    print(f"{'max':>5} {'':<20} {max(cols['od']):>8} {max(cols['ot']):>6.2f} "
          f"{max(cols['oe']):>8.2%} {max(cols['pd']):>9} {max(cols['pt']):>6.2f} "
          f"{max(cols['pe']):>8.2%} {max(cols['pvo']):>11.2%}")
    print(f"# per-design mesh: {med['pd'] / med['od']:.2f}x the unknowns, "
          f"{med['pt'] / med['ot']:.2f}x the solve time (medians)")


def sweep_table(own, planned, name: str, values, grid_mm) -> None:
    from fem.problem import build_problem

    base = {**own.center(), **SWEEP_DESIGN}
    print(f"\n# sweep of {name} over {values[0]:g}..{values[-1]:g} ({len(values)} points), "
          f"design {SWEEP_DESIGN}, the rest mid-range")
    series, meshes, walls = {}, {}, {}
    for label, space in (("per sample", own), ("per design", planned)):
        answers, topologies, t0 = [], set(), time.perf_counter()
        for v in values:
            scene = space.scene({**base, name: float(v)})
            mesh = build_problem(scene).domain.mesh
            topologies.add((mesh.r_lines.size, mesh.z_lines.size))
            answers.append(_solve(scene, grid_mm)[0])
        walls[label] = (time.perf_counter() - t0) / len(values)
        meshes[label] = len(topologies)
        series[label] = {part: np.array([getattr(a, part) for a in answers])
                         for part in ("center_um", "edge_um", "profile_um")}
    print(f"{'answer':<8} {'meshes own/plan':>15} {'step of answer':>14} "
          f"{'own/plan - 1':>12} {'step of own/plan':>16} {'kink own':>9} {'kink plan':>9}")
    for part in ("center_um", "edge_um", "profile_um"):
        own_y, plan_y = series["per sample"][part], series["per design"][part]
        ratio = own_y / plan_y - 1.0  # the per-sample mesh's departure from the smooth answer
        print(f"{part[:-3]:<8} {meshes['per sample']:>7}/{meshes['per design']:<7} "
              f"{_max_step(plan_y):>14.2e} {np.abs(ratio).max():>12.2e} "
              f"{np.abs(np.diff(ratio, axis=0)).max():>16.2e} {_kink(own_y):>9.2e} "
              f"{_kink(plan_y):>9.2e}")
    print(f"# seconds per point: own mesh {walls['per sample']:.2f}, "
          f"per-design mesh {walls['per design']:.2f}")


def _max_step(y: np.ndarray) -> float:
    """Largest relative change between neighbouring points (the physics per step)."""
    return float(np.max(np.abs(np.diff(y, axis=0)) / np.abs(y[:-1])))


def _kink(y: np.ndarray) -> float:
    """Largest relative second difference along the sweep (a profile: over its points)."""
    d2 = np.abs(y[:-2] - 2 * y[1:-1] + y[2:])
    return float(np.max(d2 / np.abs(y[1:-1])))


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=8, help="design points of the answer table")
    p.add_argument("--sweep", type=int, default=40, help="points per sweep")
    args = p.parse_args(argv)
    grid_mm = np.arange(0.0, 20.5, 1.0)  # the datasets' profile grid: 0-20 mm from the edge
    own, planned = _spaces()
    plan_table(planned)
    answer_table(own, planned, args.n, grid_mm)
    fat = own.parameter("fat_thickness_mm")
    freq = own.parameter("frequency_hz")
    sweep_table(own, planned, fat.name, np.linspace(fat.low, fat.high, args.sweep), grid_mm)
    sweep_table(own, planned, freq.name, np.linspace(freq.low, freq.high, args.sweep), grid_mm)
    return 0


if __name__ == "__main__":
    sys.exit(main())
