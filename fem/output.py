"""The JSON document of one solved scene (``hapticrom simulate --json``), schema version 1.

The document describes itself (docs/output-schema.md has the full reference, the JSON Schema
files ship in ``hapticrom/schemas``):

* ``schema_version`` (1) and ``kind`` (``"hapticrom.simulate.harmonic"``, ``.static`` or
  ``.transient``);
* ``scene``: the file name, the digest of the resolved scene (:func:`fem.scene.scene_hash`) and
  the resolved scene itself (every default filled in);
* ``analysis``: kind, drive frequency in Hz (null for a static analysis), the Fourier mode, the
  time convention and the phase reference;
* ``definitions``: what "centre", "skin axis", "edge", "magnitude" and "amplitude" mean here,
  with their radii and depths in mm;
* the values, with the unit in every key. Magnitudes and complex values never share a name:
  ``uz_amplitude_um`` is |U_z| (>= 0), ``uz_complex_um`` is ``{"re": [...], "im": [...]}``;
  a static solve gives signed ``uz_displacement_um``; a transient gives ``uz_peak_um``.

:func:`read_result` reads this version and the unversioned documents written before it (one
release of compatibility), returning the version-1 layout.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from . import SOLVER_VERSION, results
from .scene import Scene, scene_hash, scene_to_dict

__all__ = ["KINDS", "SCHEMA_VERSION", "read_result", "result_document"]

SCHEMA_VERSION = 1


class SurfaceSamples(Protocol):
    """The sampled surface every solve result carries (one solve, or one per frequency of a
    sweep along a leading axis). Amplitudes in m, distances in mm."""

    scene: Scene
    r_mm: NDArray
    U: NDArray
    center: NDArray
    edge: NDArray
    edge_mm: float | None
    centre_z_mm: float
    profile_mm: NDArray
    profile: NDArray
    meta: dict


class SimulationResult(SurfaceSamples, Protocol):
    """What a result document is made of (:class:`fem.simulation.SimulationResult` is one;
    it writes itself with :func:`result_document`, so this module names what it reads rather
    than importing it)."""

    histories: Any
    extras: dict

    @property
    def normalized_edge(self) -> float | None: ...
KINDS = {k: f"hapticrom.simulate.{k}" for k in ("harmonic", "static", "transient")}
_COMPONENTS = ("ur", "uz", "ut")

PHASE_REFERENCE = (
    "Fourier amplitudes U(r) of mode n: u_r = Re[U_r(r) cos(n theta) exp(i omega t)], "
    "u_z = Re[U_z(r) cos(n theta) exp(i omega t)], u_theta = Re[U_t(r) sin(n theta) "
    "exp(i omega t)]. Phase 0 is the phase of the drive force: for an ERM unit (n = 1) the "
    "instant its unbalance force points along theta = 0; for a normal load (n = 0) the force "
    "peak. theta = 0 is the meridian the values are sampled on.")
MAGNITUDE = ("sqrt(|U_r|^2 + |U_z|^2 + |U_t|^2): the exact displacement amplitude for n = 0 "
             "and for a rotating n = 1 load (an ERM); sqrt(2) times the RMS over theta for a "
             "one-directional n = 1 load")


def _definitions(res: SimulationResult) -> dict[str, Any]:
    centre_z = float(res.centre_z_mm)
    edge = res.edge_mm
    return {
        "centre": {
            "radius_mm": 0.0, "z_mm": centre_z,
            "text": ("the unit's face at r = 0: the skin-side face of the haptic unit (its board "
                     "underside on pogo pins, the skin itself when glued or with no unit); "
                     "z positive into the tissue, 0 = skin surface"),
        },
        "skin_axis": {
            "radius_mm": 0.0, "z_mm": 0.0,
            "text": ("the skin surface at r = 0 (the first row of surface.r_mm when a probe is "
                     "at 0); differs from the centre when the unit stands on pogo pins"),
        },
        "edge": {
            "radius_mm": edge,
            "text": ("the skin surface at the outer radius of the load footprint (the unit's "
                     "outermost ring or housing); null for a point force"),
        },
        "profile": {"text": "skin-surface samples at distances from the edge, within the model"},
        "magnitude": MAGNITUDE,
        "amplitude": _amplitude_text(res.scene.analysis.kind),
    }


def _amplitude_text(kind: str) -> str:
    if kind == "harmonic":
        return "modulus of the complex Fourier amplitude of each component (um)"
    if kind == "static":
        return "signed static displacement of each component (um); no phase"
    return ("peak |u| over the recorded run of each component (um); the magnitude of peaks is "
            "sqrt(peak_r^2 + peak_z^2 + peak_t^2)")


def _values(kind: str, U: NDArray) -> dict[str, Any]:
    """Per-component values of (n, 3) amplitudes U (m), named by what they are."""
    out: dict[str, Any] = {}
    for k, c in enumerate(_COMPONENTS):
        if kind == "harmonic":
            out[f"{c}_amplitude_um"] = (np.abs(U[:, k]) * 1e6).tolist()
            out[f"{c}_complex_um"] = results.complex_um(U[:, k])
        elif kind == "static":
            out[f"{c}_displacement_um"] = (np.real(U[:, k]) * 1e6).tolist()
        else:
            out[f"{c}_peak_um"] = (np.abs(U[:, k]) * 1e6).tolist()
    key = "magnitude_of_peaks_um" if kind == "transient" else "magnitude_um"
    out[key] = (results.magnitude(U) * 1e6).tolist()
    return out


def _point(kind: str, radius_mm: float | None, u: NDArray) -> dict[str, Any] | None:
    if radius_mm is None:
        return None
    vals = _values(kind, u[None, :])
    return {"radius_mm": float(radius_mm),
            **{k: (v[0] if isinstance(v, list) else {p: v[p][0] for p in v})
               for k, v in vals.items()}}


def _histories(res: SimulationResult) -> dict[str, Any]:
    h = res.histories
    n = res.r_mm.size
    labels = [("probe", i) for i in range(n)] + [("centre", n)]
    if res.edge_mm is not None:
        labels.append(("edge", n + 1))
    points = []
    for label, i in labels:
        u = h.u[:, i]
        points.append({"label": label, "radius_mm": float(h.radii[i] * 1e3),
                       **{f"{c}_um": (u[:, k] * 1e6).tolist()
                          for k, c in enumerate(_COMPONENTS)},
                       "magnitude_um": (np.linalg.norm(u, axis=-1) * 1e6).tolist()})
    return {"t_ms": (h.t * 1e3).tolist(), "meridian": "theta = 0",
            "text": "displacement time histories u(t) on the theta = 0 meridian (um)",
            "points": points}


def result_document(res: SimulationResult, scene_name: str | None = None) -> dict[str, Any]:
    """The version-1 JSON document of a solved scene (see the module docstring)."""
    a = res.scene.analysis
    kind = a.kind
    doc: dict[str, Any] = {
        "schema_version": SCHEMA_VERSION,
        "kind": KINDS[kind],
        "solver_version": SOLVER_VERSION,
        "scene": {"name": scene_name, "digest": scene_hash(res.scene),
                  "resolved": scene_to_dict(res.scene)},
        "analysis": {
            "kind": kind,
            "frequency_hz": None if kind == "static" else float(res.meta["frequency_hz"]),
            "fourier_mode": int(res.meta["modes"][0]),
            "time_convention": "exp(+i omega t)" if kind == "harmonic" else None,
            "phase_reference": PHASE_REFERENCE if kind == "harmonic" else None,
        },
        "definitions": _definitions(res),
        "surface": {"r_mm": res.r_mm.tolist(), **_values(kind, res.U)},
        "centre": _point(kind, 0.0 if res.edge_mm is not None else None, res.center),
        "edge": _point(kind, res.edge_mm, res.edge),
        "normalized_edge": res.normalized_edge,
        "profile": {"distance_from_edge_mm": res.profile_mm.tolist(),
                    **_values(kind, res.profile)},
        "meta": dict(res.meta),
        "extras": dict(res.extras),
    }
    if res.histories is not None:
        doc["histories"] = _histories(res)
    return doc


# ----------------------------------------------------------------------------- reading back


def read_result(doc: dict[str, Any]) -> dict[str, Any]:
    """A simulate document in the version-1 layout: version 1 is returned unchanged; an
    unversioned (pre-1) document is converted, reading its old keys (``uz_um`` complex under
    ``surface``, a magnitude under ``profile``; ``center_amplitude_um``,
    ``edge_amplitude_um``). Old documents stay readable for one release. Raises ValueError
    naming the key for anything else."""
    if not isinstance(doc, dict):
        raise ValueError("a simulate result must be a JSON object")
    version = doc.get("schema_version")
    if version == SCHEMA_VERSION:
        for key in ("kind", "surface", "analysis"):
            if key not in doc:
                raise ValueError(f"schema_version 1 document without the key {key!r}")
        return doc
    if version is not None:
        raise ValueError(f"schema_version = {version!r}: this hapticrom reads 1 and "
                         "unversioned (pre-1) documents")
    return _from_v0(doc)


def _from_v0(doc: dict[str, Any]) -> dict[str, Any]:
    try:
        surf, prof, meta = doc["surface"], doc["profile"], doc.get("meta", {})
        kind = "transient" if "histories" in doc else "harmonic"
        U = np.column_stack([np.asarray(surf[f"{c}_um"]["re"])
                             + 1j * np.asarray(surf[f"{c}_um"]["im"]) for c in _COMPONENTS])
        centre, edge = doc.get("center_amplitude_um"), doc.get("edge_amplitude_um")
        out = {
            "schema_version": SCHEMA_VERSION, "kind": KINDS[kind], "converted_from": 0,
            "solver_version": meta.get("solver_version"),
            "scene": {"name": None, "digest": None, "resolved": None},
            "analysis": {"kind": kind, "frequency_hz": None,
                         "fourier_mode": (meta.get("modes") or [None])[0],
                         "time_convention": meta.get("time_convention"),
                         "phase_reference": None},
            "surface": {"r_mm": list(surf["r_mm"]), "magnitude_um": list(surf["magnitude_um"])},
            "centre": None if centre is None else {"radius_mm": 0.0, "magnitude_um": centre},
            "edge": None if edge is None else {"radius_mm": None, "magnitude_um": edge},
            "normalized_edge": doc.get("normalized_edge"),
            "profile": {"distance_from_edge_mm": list(prof["distance_from_edge_mm"]),
                        "uz_amplitude_um": list(prof["uz_um"]),
                        "magnitude_um": list(prof["magnitude_um"])},
            "meta": dict(meta),
        }
    except KeyError as err:
        raise ValueError(f"unversioned simulate result without the key {err.args[0]!r}"
                         ) from None
    for k, c in enumerate(_COMPONENTS):
        if kind == "transient":  # v0 wrote the peaks as complex numbers with im = 0
            out["surface"][f"{c}_peak_um"] = np.abs(U[:, k]).tolist()
        else:
            out["surface"][f"{c}_complex_um"] = dict(surf[f"{c}_um"])
            out["surface"][f"{c}_amplitude_um"] = np.abs(U[:, k]).tolist()
    if kind == "transient":
        out["surface"]["magnitude_of_peaks_um"] = out["surface"].pop("magnitude_um")
        out["profile"] = {"distance_from_edge_mm": out["profile"]["distance_from_edge_mm"],
                          "uz_peak_um": out["profile"]["uz_amplitude_um"],
                          "magnitude_of_peaks_um": out["profile"]["magnitude_um"]}
        out["definitions"] = {"amplitude": _amplitude_text("transient")}
        h = doc["histories"]
        out["histories"] = {"t_ms": (np.asarray(h["t_s"]) * 1e3).tolist(),
                            "points": [{"label": "probe", **p} for p in h["points"]]}
    return out


def describe_design(scene: Any) -> str:
    """One line naming the design of a scene, for titles and summaries: the unit's
    orientation, attachment and rings, or the load (kind, direction, radius)."""
    u = scene.unit
    if u is not None and scene.load.kind.is_unit:
        rings = ", ".join(r.name for r in u.encapsulation) or "no rings"
        return f"{scene.load.kind.value}: {u.orientation}, {u.attachment}, rings: {rings}"
    load = scene.load
    where = (f"point force {load.force_N:g} N" if "point" in load.kind.value
             else f"patch r = {load.radius_mm:g} mm, {load.amplitude_Pa:g} Pa")
    return f"{load.direction} {where}"
