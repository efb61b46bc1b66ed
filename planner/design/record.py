"""The design record: what ``hapticrom design`` found, as a versioned, sealed JSON document.

Like ``plan.json`` (:mod:`planner.plan_record`): ``schema_version`` (:data:`SCHEMA_VERSION`),
``kind`` (:data:`KIND`) and ``design_sha256``, the sha256 hex digest of the canonical JSON of
the record without that key (:func:`planner.plan_record.canonical_digest`, the plan's form).
:func:`check_design_record` reads one back as untrusted input: its header, its digest
(``sealed`` or ``edited``) and the types of the entries a reader uses.

Contents: the request (model, array, site, frequencies, criterion, space, search), the
search's statistics, every evaluated design in the order the optimiser asked for it
(``history``: inputs, best frequency, pitches, own amplitude, perceptibility, score), the
Pareto front (indices into the history), the reference units, the winner, the share of the
winner's criterion resting on the log-slope extension beyond the models' profile
(``extrapolation``), with ``--tissue`` the posterior re-ranking, and the FE check
(``verify``) when it ran.
"""

from __future__ import annotations

from typing import Any

from planner.design.evaluate import Evaluation
from planner.design.run import DesignOutcome, pareto_front
from planner.plan_record import PlanRecordError, canonical_digest

__all__ = ["DIGEST_KEY", "KIND", "SCHEMA_VERSION", "check_design_record", "design_record"]

SCHEMA_VERSION = 1
KIND = "hapticrom.design"
DIGEST_KEY = "design_sha256"
BEYOND_FLAG = 0.01  # a share of the leakage power beyond the profile worth flagging


def _extrapolation(outcome: DesignOutcome) -> dict[str, Any]:
    """How much of the criterion rests on the profile's log-slope extension."""
    feasible = [e for e in outcome.history if e.feasible]
    w = outcome.winner
    shares = sorted(e.beyond_profile for e in feasible)
    return {"profile_end_from_edge_mm": outcome.evaluator.profile_end_mm,
            "winner_leakage_share_beyond_profile": None if w is None else
            round(w.beyond_profile, 4),
            "feasible_designs": len(feasible),
            "designs_flagged": sum(s >= BEYOND_FLAG for s in shares),
            "share_median": None if not shares else round(shares[len(shares) // 2], 4),
            "share_max": None if not shares else round(shares[-1], 4),
            "flag_from": BEYOND_FLAG,
            "meaning": "share of the worst site's leakage power that comes from neighbours "
                       "beyond the model profile's last point (the log-slope extension of "
                       "planner.crosstalk), at each design's pitch"}


def _request(outcome: DesignOutcome) -> dict[str, Any]:
    req, lay = outcome.request, outcome.layout
    crit = lay.criterion
    sp = req.space
    return {"model": lay.model, "array": {"rows": lay.rows, "cols": lay.cols, "grid": lay.grid,
                                          "min_pitch_mm": lay.min_pitch_mm,
                                          "max_pitch_mm": lay.max_pitch_mm},
            "site": dict(lay.site), "frequencies_hz": list(lay.frequencies_hz),
            "band_step_hz": req.band_step_hz,
            "criterion": {"kind": crit.kind, "max_ratio": crit.max_ratio,
                          "superposition": crit.superposition, "drive_level": crit.drive_level,
                          "holds_at": crit.holds_at},
            "perceptibility_threshold": outcome.evaluator.curve.source,
            "space": {"orientations": list(sp.orientations), "attachments": list(sp.attachments),
                      "n_rings": list(sp.n_rings), "materials": sp.materials,
                      "catalogue": [s.name for s in outcome.space.catalogue.chosen],
                      "dimensions": [d.name for d in outcome.space.dimensions]},
            "verify_top": req.verify_top,
            "references": [{"name": p.name, "scene": p.path} for p in req.references]}


def design_record(outcome: DesignOutcome, verify: dict[str, Any] | None = None,
                  outputs: dict[str, str] | None = None) -> dict[str, Any]:
    """The sealed record of ``outcome`` (``verify``: the FE check's block)."""
    hist = outcome.history
    w = outcome.winner

    def ev(e: Evaluation | None) -> dict[str, Any] | None:
        return None if e is None else e.to_dict()

    body: dict[str, Any] = {
        "request": _request(outcome),
        "search": outcome.search, "wall_s": round(outcome.wall_s, 3),
        "dropped_frequencies": outcome.evaluator.dropped,
        "history": [e.to_dict() for e in hist],
        "pareto": pareto_front(hist),
        "references": [e.to_dict() for e in outcome.references],
        "winner": ev(w),
        "ranking": [e.order for e in outcome.ranking[:20]],
        "extrapolation": _extrapolation(outcome),
        "tissue": outcome.tissue, "posterior": outcome.posterior or None,
        "timing": None if outcome.plan is None else outcome.plan.timing,
        "verify": verify, "outputs": outputs or {}}
    return seal_design(body)


def seal_design(body: dict[str, Any]) -> dict[str, Any]:
    """``body`` with the header and its digest."""
    out = {"schema_version": SCHEMA_VERSION, "kind": KIND,
           **{k: v for k, v in body.items() if k not in ("schema_version", "kind", DIGEST_KEY)}}
    out[DIGEST_KEY] = canonical_digest(out, DIGEST_KEY)
    return out


def check_design_record(d: Any) -> str:
    """``sealed`` when the digest matches, ``edited`` when it does not; raises
    :class:`PlanRecordError` naming the key for a record of another kind or version, or
    with a malformed header or history."""
    if not isinstance(d, dict):
        raise PlanRecordError("<file>", "a design record must be a JSON object")
    if d.get("kind") != KIND:
        raise PlanRecordError("kind", f"kind = {d.get('kind')!r}: expected {KIND!r}")
    if d.get("schema_version") != SCHEMA_VERSION:
        raise PlanRecordError("schema_version", f"schema_version = {d.get('schema_version')!r}"
                              f": this reader knows {SCHEMA_VERSION}")
    digest = d.get(DIGEST_KEY)
    if not isinstance(digest, str) or len(digest) != 64:
        raise PlanRecordError(DIGEST_KEY, f"{DIGEST_KEY} = {digest!r}: expected 64 hex digits")
    hist = d.get("history")
    if not isinstance(hist, list) or not all(isinstance(h, dict) and "score" in h
                                             for h in hist):
        raise PlanRecordError("history", "history: expected a list of evaluated designs")
    return "sealed" if canonical_digest(d, DIGEST_KEY) == digest else "edited"
