"""Integrity of a dataset directory: the manifest is what was written, the parts belong to it.

* ``digest``: sha256 over the manifest's own content (canonical JSON without the digest),
  written with every manifest save. A hand edit (a changed seed, range, solver entry, a
  deleted section) no longer matches it. Manifests written before the digest existed have
  none; for them, and in addition for all, the semantic checks below still apply.
* Semantic checks: every section present; the recorded space hashes to the recorded
  ``space_hash``; the sampling seed is the space's; the current solver is in the history.
* Parts: the manifest records every part with a digest of its rows
  (:mod:`surrogate.data.digests`); in addition no (source, sample_id) is in two parts and no
  part was written for another space (each part records the space hash it was written for).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Protocol

from surrogate.data.errors import DatasetError
from surrogate.data.provenance import solver_key

__all__ = ["REQUIRED_SECTIONS", "manifest_digest", "manifest_problems", "part_problems"]

REQUIRED_SECTIONS = ("space", "space_hash")


class Store(Protocol):
    """What the checks read of a dataset (:class:`surrogate.data.store.Store` is one; the
    store runs these checks, so this module names what it needs rather than importing it)."""

    manifest: dict[str, Any]

    @property
    def space(self) -> Any: ...

    def parts(self) -> list[Path]: ...

    def part_metadata(self, part: Path) -> dict[str, Any]: ...

    def read_part(self, part: Path, columns: Any = None) -> Any: ...
#: A dataset that records solver runs (``runs``, written by generate) has all of these.
GENERATED_SECTIONS = ("sampling", "solver", "solver_history")


def manifest_digest(manifest: Mapping[str, Any]) -> str:
    """sha256 hex of the manifest's canonical JSON, the ``digest`` key excluded."""
    body = {k: v for k, v in manifest.items() if k != "digest"}
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


def manifest_problems(store: Store) -> list[str]:
    """What is wrong with ``store``'s manifest (empty when it is as written)."""
    m = store.manifest
    problems = []
    if "digest" in m and m["digest"] != manifest_digest(m):
        problems.append("its content does not match its digest: it was edited after it was "
                        "written")
    elif "parts" in m and "digest" not in m:
        problems.append("it records parts but has no digest: it was edited after it was "
                        "written")
    required = REQUIRED_SECTIONS + (GENERATED_SECTIONS if m.get("runs") else ())
    missing = [key for key in required if key not in m]
    if missing:
        return [*problems, f"the {', '.join(missing)} section(s) are missing"]
    try:
        space = store.space
    except (ValueError, KeyError, TypeError) as err:
        return [*problems, f"the recorded space is not a valid space: {err}"]
    if space.space_hash() != m["space_hash"]:
        problems.append("the recorded space does not hash to the recorded space_hash (the "
                        "space was edited)")
    if "sampling" not in m or "solver" not in m:
        return problems  # an ingested or merged dataset: no sampling, no solver of its own
    if m["sampling"].get("seed") != space.seed:
        problems.append(f"sampling.seed = {m['sampling'].get('seed')!r} is not the space's "
                        f"seed {space.seed!r}")
    history = {solver_key(s) for s in m.get("solver_history", []) if isinstance(s, Mapping)}
    if not isinstance(m["solver"], Mapping) or solver_key(m["solver"]) not in history:
        problems.append("the current solver entry is not in solver_history (edited)")
    return problems


def part_problems(store: Store) -> list[str]:
    """Parts that repeat another part's samples or were written for another space."""
    problems = []
    first: dict[tuple[str, str], str] = {}
    for part in store.parts():
        try:
            recorded = store.part_metadata(part).get("space_hash")
        except DatasetError:
            continue  # unreadable: reported (validate) or raised (read) on its own
        if recorded is not None and recorded != store.manifest.get("space_hash"):
            problems.append(f"{part.name} was written for another space ({recorded[:12]}...)")
            continue
        try:
            t = store.read_part(part, ["source", "sample_id"]).to_pydict()
        except DatasetError:
            continue  # unreadable: reported (validate) or raised (read) on its own
        repeats: dict[str, int] = {}
        for key in zip(t["source"], t["sample_id"], strict=True):
            if key in first:
                repeats[first[key]] = repeats.get(first[key], 0) + 1
            else:
                first[key] = part.name
        problems += [f"{part.name} repeats {n} sample(s) of {other} (a copied part file?)"
                     for other, n in repeats.items()]
    return problems
