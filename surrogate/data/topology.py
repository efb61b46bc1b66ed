"""Dispatch order for generation: samples of one mesh topology run back to back.

The solver caches per-topology work in each worker process (the scatter map of the assembly,
about 50 ms to build on the default forearm; the sparse factorisation's symbolic analysis),
keyed by the sparsity pattern of the system. Samples arrive in design-sequence (Sobol) order,
in which neighbours rarely share a mesh, because continuous parameters (fat thickness,
frequency through the wavelength rule, ring moduli) move grid lines and change their counts in
steps. :func:`topology_chunks` groups the samples by :func:`topology_key` and cuts the groups
into chunks, longest first, so a worker meets each topology in a run of consecutive samples.

The key is computed from the discretised problem (mesh, constraints, ties, extra operators),
built exactly as the solver builds it, so two scenes share a key iff their systems share a
sparsity pattern. A key is an ordering hint only: the caches are keyed on the real pattern,
and each sample's result depends on its scene alone, so grouping changes speed, never rows.
"""

from __future__ import annotations

import hashlib
import itertools
import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

from fem.cost import check_cost
from fem.problem import build_problem
from fem.scene import Scene, scene_from_dict

if TYPE_CHECKING:
    from fem.scene import Scene

__all__ = ["MAX_CHUNK", "default_cap", "topology_chunks", "topology_key"]

#: Largest chunk the default sizing makes (samples): bounds the work a killed run loses per
#: worker and the interval between progress updates, as the ungrouped chunks did.
MAX_CHUNK = 32

T = TypeVar("T")


def topology_key(scene: Scene | Mapping[str, Any]) -> str:
    """A digest of what fixes the sparsity pattern of a scene's system: the analysis path
    (steady or transient), Fourier mode, element order, grid size, which cells hold elements,
    the axis, the constrained and tied nodes, and the dofs of the extra operators (pogo pins).
    These determine the dof map and the element dofs the solver's caches are keyed on.

    Costs about 5 ms from a :class:`fem.scene.Scene` (the problem build, no element matrices),
    a few more from a scene dict (parsing). A scene the solver would refuse (invalid, or above
    the size limit) gets a key of its own: it is grouped with nothing, and nothing large is
    allocated here."""
    try:
        parsed = scene if isinstance(scene, Scene) else scene_from_dict(scene)
        check_cost(parsed)
        problem = build_problem(parsed)
    except Exception as err:  # the worker reports it; here it only needs a group of its own
        return "unbuilt:" + hashlib.blake2b(repr((err, scene)).encode(),
                                            digest_size=16).hexdigest()
    domain, mesh = problem.domain, problem.domain.mesh
    transient = parsed.analysis.kind == "transient"
    axis = mesh.nodes_where(lambda r, z: r <= 1e-12 * max(1.0, float(mesh.r_lines[-1])))
    h = hashlib.blake2b(digest_size=16)
    parts = [np.array([transient, problem.mode, mesh.order, mesh.r_lines.size,
                       mesh.z_lines.size]),
             np.searchsorted(mesh.r_lines, mesh.cell_r0),  # the cells holding elements
             np.searchsorted(mesh.z_lines, mesh.cell_z0), axis]
    for nodes, component in domain.constraints:
        parts += [np.array([-1, component]), np.asarray(nodes)]
    for followers, leaders, component in domain.ties:
        parts += [np.array([-2, component]), np.asarray(followers), np.asarray(leaders)]
    for _, edofs, _ in problem.extra:
        parts += [np.array([-3, *np.shape(edofs)]), np.asarray(edofs).ravel()]
    for part in parts:  # sizes first: equal concatenations of different parts stay apart
        h.update(np.int64(part.size).tobytes())
        h.update(np.ascontiguousarray(part, dtype=np.int64).tobytes())
    return h.hexdigest()


def topology_chunks(items: Sequence[T], keys: Sequence[str], size: int,
                    cap: int) -> list[list[T]]:
    """Chunks of ``items`` with every topology's samples consecutive, longest chunks first.

    Items sharing a key form a group (in input order). A group longer than ``cap`` is split
    into near-equal pieces of at most ``cap``; pieces shorter than ``size`` are packed together
    up to ``size``. Chunks come out longest first (equal lengths in input order), so a pool
    that hands the next chunk to the next free worker ends with short chunks on every worker:
    the load stays balanced. Every item appears exactly once."""
    if len(items) != len(keys):
        raise ValueError(f"{len(items)} items but {len(keys)} keys")
    if not 1 <= size <= cap:
        raise ValueError(f"need 1 <= size <= cap, got size = {size}, cap = {cap}")
    groups: dict[str, list[T]] = {}
    for item, key in zip(items, keys, strict=True):
        groups.setdefault(key, []).append(item)
    pieces = [piece for group in groups.values() for piece in _split(group, cap)]
    pieces.sort(key=len, reverse=True)  # stable: equal lengths keep input order
    chunks: list[list[T]] = []
    for piece in pieces:
        if chunks and len(chunks[-1]) + len(piece) <= size:
            chunks[-1].extend(piece)
        else:
            chunks.append(list(piece))
    return chunks


def default_cap(size: int, n_items: int, workers: int) -> int:
    """Longest chunk a group may fill when the caller did not fix the chunk size: up to
    :data:`MAX_CHUNK`, and at most half a worker's fair share, so that even a single topology
    leaves every worker at least two chunks; never below ``size``."""
    return max(size, min(MAX_CHUNK, math.ceil(n_items / (2 * workers))))


def _split(group: list[T], cap: int) -> list[list[T]]:
    """``group`` cut into the fewest near-equal consecutive pieces of at most ``cap``, the
    longer ones first (so sorting by length keeps a group's pieces in order)."""
    count = math.ceil(len(group) / cap)
    short, longer = divmod(len(group), count)
    bounds = [0, *itertools.accumulate([short + 1] * longer + [short] * (count - longer))]
    return [group[a:b] for a, b in itertools.pairwise(bounds)]
