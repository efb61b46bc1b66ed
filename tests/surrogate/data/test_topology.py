"""Dispatch grouped by mesh topology: the key tracks the sparsity pattern, chunks hold every
sample once and stay balanced, and the stored rows equal those of plan-order dispatch."""

from __future__ import annotations

import copy
import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

import surrogate.data.generate as gen
from fem.assembly import assemble_matrix, build_dofmap
from fem.elements import dofs_per_node
from fem.problem import build_problem
from fem.scene import scene_from_dict, scene_to_dict
from fem.solve import interior_dofs
from surrogate.data.backends import PoolBackend
from surrogate.data.plan import plan_samples
from surrogate.data.space import space_from_dict
from surrogate.data.topology import MAX_CHUNK, default_cap, topology_chunks, topology_key

#: Coarse unit scenes (pogo pins or glued, 0-2 rings) whose fat thickness moves z lines in
#: steps: several samples share a mesh, several do not.
UNIT_SPACE: dict[str, Any] = {
    "space": {"name": "topology-test", "seed": 3},
    "base": {"load": {"kind": "unit"},
             "analysis": {"kind": "harmonic", "frequency_hz": 150.0},
             "mesh": {"near_size_mm": 1.0, "far_size_mm": 4.0, "order": 2,
                      "follow_wavelength": False},
             "tissue": {"radius_mm": 30.0},
             "unit": {"encapsulation": [
                 {"name": "r1", "E_kPa": 200.0, "density_kg_m3": 1070.0, "nu": 0.49},
                 {"name": "r2", "E_kPa": 400.0, "density_kg_m3": 1070.0, "nu": 0.49}]}},
    "parameter": [
        {"name": "attachment", "type": "categorical", "path": "unit.attachment",
         "choices": ["glued", "pogo"]},
        {"name": "n_rings", "type": "integer", "path": "unit.encapsulation",
         "map": "list_length", "low": 0, "high": 2},
        {"name": "fat_thickness_mm", "type": "continuous",
         "path": "tissue.layer[1].thickness_mm", "low": 3.0, "high": 8.0},
        {"name": "skin_E_kPa", "type": "continuous", "path": "tissue.layer[0].E_kPa",
         "low": 20.0, "high": 120.0},
    ],
}


def _scene(fat_mm: float = 10.0, skin_kPa: float = 49.0) -> dict[str, Any]:
    """A coarse point-load scene on the default forearm with this fat thickness [mm] and
    skin Young's modulus [kPa]; fixed side and base (an absorber's thickness would follow the
    tissue's wave speed, so the modulus would move its lines)."""
    scene = scene_to_dict(scene_from_dict({
        "analysis": {"kind": "harmonic", "frequency_hz": 150.0},
        "mesh": {"near_size_mm": 1.0, "far_size_mm": 4.0, "order": 1,
                 "follow_wavelength": False},
        "tissue": {"radius_mm": 30.0, "side": "fixed", "base": "fixed"}}))
    scene["tissue"]["layer"][0]["E_kPa"] = skin_kPa
    scene["tissue"]["layer"][1]["thickness_mm"] = fat_mm
    return scene


def _pattern(scene: dict[str, Any]) -> tuple[bytes, ...]:
    """The sparsity pattern of the system the steady solve assembles (fem.solve.solve_mode:
    element-interior dofs fixed and condensed out, extra operators added)."""
    problem = build_problem(scene_from_dict(scene))
    domain, mode = problem.domain, problem.mode
    mesh = domain.mesh
    inner = interior_dofs(mode, mesh.order)
    fixed = domain.fixed()
    if inner.size:
        centres = mesh.elements[:, 1 + (mesh.order + 1)]
        fixed += [(centres, c) for c in range(dofs_per_node(mode))]
    dm = build_dofmap(mesh, mode, fixed, ties=domain.ties)
    outer = np.setdiff1d(np.arange(dm.element_dofs.shape[1]), inner)
    dm = replace(dm, element_dofs=dm.element_dofs[:, outer])
    nd = outer.size
    A = assemble_matrix(dm, np.ones((mesh.n_elements, nd, nd)))
    for _, edofs, Ke in problem.extra:
        A = A + assemble_matrix(dm, np.ones_like(Ke), edofs)
    A.sort_indices()
    return A.shape[0].to_bytes(8, "little"), A.indptr.tobytes(), A.indices.tobytes()


def test_the_key_ignores_moduli_and_follows_line_counts() -> None:
    base = topology_key(_scene())
    assert not base.startswith("unbuilt:")
    assert topology_key(_scene(skin_kPa=120.0)) == base
    assert _pattern(_scene(skin_kPa=120.0)) == _pattern(_scene())
    assert topology_key(scene_from_dict(_scene(skin_kPa=120.0))) == base  # a Scene object too
    thicker = _scene(fat_mm=22.0)
    assert topology_key(thicker) != base
    assert _pattern(thicker) != _pattern(_scene())  # a line count changed: another pattern
    # a scene the solver refuses gets a group of its own, not an exception
    bad = {"analysis": {"kind": "harmonic", "frequency_hz": -1.0}}
    assert topology_key(bad) != topology_key(copy.deepcopy(_scene()))
    assert topology_key(bad).startswith("unbuilt:")


def test_equal_keys_iff_equal_sparsity_patterns() -> None:
    planned, _ = plan_samples(space_from_dict(UNIT_SPACE), 24)
    by_key: dict[str, list[int]] = {}
    by_pattern: dict[tuple[bytes, ...], list[int]] = {}
    for i, p in enumerate(planned):
        by_key.setdefault(topology_key(p.scene), []).append(i)
        by_pattern.setdefault(_pattern(p.scene), []).append(i)
    assert sorted(by_key.values()) == sorted(by_pattern.values())
    assert 1 < len(by_key) < len(planned)  # the space has shared and distinct meshes


@pytest.mark.parametrize(("n", "workers", "size", "n_keys"),
                         [(64, 2, 2, 1), (64, 2, 2, 7), (256, 2, 8, 40), (100, 3, 2, 100),
                          (2048, 2, 32, 481), (37, 4, 1, 5)])
def test_chunks_hold_every_sample_once_grouped_and_balanced(n: int, workers: int, size: int,
                                                            n_keys: int) -> None:
    rng = np.random.default_rng(n + n_keys)
    keys = [f"k{k}" for k in rng.zipf(1.5, n) % n_keys]  # a few large groups, many small
    cap = default_cap(size, n, workers)
    chunks = topology_chunks(list(range(n)), keys, size, cap)
    flat = [i for c in chunks for i in c]
    assert sorted(flat) == list(range(n))  # every sample exactly once
    assert max(len(c) for c in chunks) <= cap <= max(size, MAX_CHUNK)
    assert cap <= max(size, -(-n // (2 * workers)))  # never above half a worker's share
    groups: dict[str, list[int]] = {}
    for i, k in enumerate(keys):
        groups.setdefault(k, []).append(i)
    for members in groups.values():
        # a group is split only when it exceeds the cap, into runs kept in plan order
        runs = [[i for i in c if keys[i] == keys[members[0]]] for c in chunks]
        runs = [r for r in runs if r]
        assert len(runs) == -(-len(members) // cap)
        assert [i for r in runs for i in r] == members
        for c in chunks:  # within a chunk a group's samples are consecutive
            at = [j for j, i in enumerate(c) if keys[i] == keys[members[0]]]
            assert at == list(range(at[0], at[0] + len(at))) if at else True
    # longest first: a pool handing the next chunk to the next free worker ends with the
    # workers level to within one chunk of at most the cap, however large a group is
    lengths = [len(c) for c in chunks]
    assert lengths == sorted(lengths, reverse=True) or all(x <= size for x in lengths[
        next(j for j, x in enumerate(lengths) if x <= size):])
    loads = np.zeros(workers)
    for c in chunks:
        loads[np.argmin(loads)] += len(c)
    assert loads.max() - loads.min() <= cap
    if n_keys == 1:  # one giant group: spread over every worker, not handed to one
        assert loads.max() - loads.min() <= size and len(chunks) >= 2 * workers


def test_bad_chunk_arguments_are_refused() -> None:
    with pytest.raises(ValueError, match="2 items but 1 keys"):
        topology_chunks([1, 2], ["a"], 1, 1)
    with pytest.raises(ValueError, match="size <= cap"):
        topology_chunks([1], ["a"], 4, 2)


def _submitted(monkeypatch: pytest.MonkeyPatch) -> list[list[int]]:
    """Record the sample frequencies (identifying the scenes) of every submitted chunk."""
    chunks: list[list[float]] = []
    real = PoolBackend.submit

    def submit(self: PoolBackend, payload: str) -> Any:
        chunks.append([s["tissue"]["layer"][1]["thickness_mm"] for s in json.loads(payload)])
        return real(self, payload)

    monkeypatch.setattr(PoolBackend, "submit", submit)
    return chunks


def test_grouped_rows_equal_plan_order_rows(tmp_path: Path,
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    space = space_from_dict(UNIT_SPACE)
    n = 16
    planned, _ = plan_samples(space, n)
    fat = {p.values["fat_thickness_mm"]: topology_key(p.scene) for p in planned}
    chunks = _submitted(monkeypatch)
    monkeypatch.setattr(gen, "GROUP_BY_TOPOLOGY", False)
    gen.generate(space, n, tmp_path / "plan", workers=1, chunk=2, progress=False)
    plan_chunks = list(chunks)
    chunks.clear()
    monkeypatch.setattr(gen, "GROUP_BY_TOPOLOGY", True)
    rep = gen.generate(space, n, tmp_path / "grouped", workers=2, progress=False)
    assert rep.new_ok == n
    # the grouped run sent a topology's samples together, the plan-order run did not
    grouped_keys = [[fat[f] for f in c] for c in chunks]
    assert any(len(c) > 1 and len(set(c)) == 1 for c in grouped_keys)
    assert sorted(f for c in chunks for f in c) == sorted(f for c in plan_chunks for f in c)
    a, b = (pd.read_parquet(tmp_path / d).sort_values("sample_index").reset_index(drop=True)
            for d in ("plan", "grouped"))
    assert a["sample_index"].tolist() == [p.index for p in planned]
    cols = [c for c in a.columns if c != "wall_s"]
    assert list(b.columns) == list(a.columns)
    for col in cols:  # bit for bit
        for x, y in zip(a[col], b[col], strict=True):
            if isinstance(x, np.ndarray):
                assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), col
            else:
                assert (pd.isna(x) and pd.isna(y)) or x == y, col


@pytest.mark.parametrize("grouped", [True, False])
def test_the_dispatch_queue_hands_out_every_sample_once_window_by_window(
        monkeypatch: pytest.MonkeyPatch, grouped: bool) -> None:
    planned, _ = plan_samples(space_from_dict(UNIT_SPACE), 20)
    monkeypatch.setattr(gen, "GROUP_BY_TOPOLOGY", grouped)
    monkeypatch.setattr(gen, "GROUP_WINDOW", 8)
    queue = gen._DispatchQueue(planned, 2, None, 2)
    chunks = []
    while queue:
        chunks.append(queue.popleft())
    assert sorted(p.index for c in chunks for p in c) == [p.index for p in planned]
    # windows of 8 in plan order: no chunk mixes samples of two windows
    windows = [{p.index for p in planned[i : i + 8]} for i in range(0, 20, 8)]
    assert all(any({p.index for p in c} <= w for w in windows) for c in chunks)
    if not grouped:  # plan order, chunks of 2
        assert [p.index for c in chunks for p in c] == [p.index for p in planned]
        assert [len(c) for c in chunks] == [2] * 10
