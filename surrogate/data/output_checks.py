"""``dataset validate`` and ``dataset info`` for the output columns: complex single-frequency
amplitudes and sweeps over a band (:mod:`surrogate.data.columns`).

Checks on the generated "ok" rows (problems name a sample and the column):

* complex single-frequency columns: null (not stored for that row), or finite and
  consistent with the stored magnitudes (sqrt(sum of re^2 + im^2 over r, z, t) equals
  ``center_amplitude_um`` / ``edge_amplitude_um`` / ``profile_magnitude_um``, abs(U_z)
  equals ``profile_uz_um``, to a relative 1e-9 of the field's largest value);
* sweep columns: every list finite and of its length (n_f for centre and edge, n_f * n_p for
  the profile), the row's frequencies equal to the manifest's band and its profile distances
  to the manifest's grid, the error estimate finite and >= 0, at least one full solve.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from surrogate.data.columns import COMPLEX_FIELDS, COMPONENTS, SWEEP_FIELDS

__all__ = ["check_outputs", "outputs_summary"]

_RTOL = 1e-9
_MAX_LISTED = 5
_SWEEP_LISTS = [f.name for f in SWEEP_FIELDS if f.name.startswith("sweep_")
                and f.name.endswith("_um")]


def outputs_summary(manifest: Mapping[str, Any], columns: list[str]) -> str:
    """One line saying what the rows hold."""
    band = manifest.get("band")
    grid = manifest.get("profile_grid_mm") or []
    if band:
        f = band.get("frequency_hz") or []
        where = f"{f[0]:g}-{f[-1]:g} Hz" if f else "?"
        stored = (f"stored as codes within {manifest['codec'].get('bound')} of the band "
                  "maximum" if isinstance(manifest.get("codec"), Mapping) else "float32")
        return (f"complex sweeps: {len(f)} frequencies {where}, profile {len(grid)} points "
                f"(centre, edge, profile: r, z, t re/im; {stored})")
    if "center_uz_re_um" in columns:
        return "magnitudes and complex amplitudes (centre, edge, profile: r, z, t re/im)"
    if "history_center_um" in columns and manifest.get("analysis_kind") == "transient":
        return "time histories (transient)"
    return "magnitudes only (written before complex amplitudes were stored)"


def check_outputs(manifest: Mapping[str, Any], ok: Any) -> list[str]:
    """Problems of the output columns of the generated ok rows ``ok`` (a DataFrame)."""
    if manifest.get("band"):
        return _check_sweeps(manifest, ok)
    if "center_uz_re_um" in ok.columns:
        return _check_complex(ok)
    return []


def _complex(ok: Any, prefix: str) -> np.ndarray | None:
    names = [f"{prefix}_u{c}_{p}_um" for c in COMPONENTS for p in ("re", "im")]
    if not all(n in ok.columns for n in names):
        return None
    return np.stack([ok[n].to_numpy(dtype=float) for n in names], axis=1)


def _check_complex(ok: Any) -> list[str]:
    problems = []
    for where in ("center", "edge"):
        parts = _complex(ok, where)
        if parts is None:
            continue
        mag = ok[f"{where}_amplitude_um"].to_numpy(dtype=float)
        stored = ~np.isnan(parts).all(axis=1)  # rows without complex values (null) are allowed
        have = np.isfinite(mag) & stored
        if not np.all(np.isfinite(parts[have])) or (stored & ~np.isfinite(mag)).any():
            problems.append(f"generated ok rows with non-finite or partial "
                            f"{where}_u*_re/im_um")
            continue
        from_parts = np.sqrt((parts[have] ** 2).sum(axis=1))
        bad = np.abs(from_parts - mag[have]) > _RTOL * max(float(np.max(mag[have], initial=0)),
                                                          1e-300)
        if bad.any():
            sid = ok["sample_id"].to_numpy()[have][bad][0]
            problems.append(f"{int(bad.sum())} rows' complex {where} amplitudes do not give "
                            f"their {where}_amplitude_um (e.g. sample {sid[:12]})")
    names = [f.name for f in COMPLEX_FIELDS if f.name.startswith("profile_")]
    for row in ok[["sample_id", "profile_magnitude_um", "profile_uz_um", *names]].itertuples(
            index=False):
        problem = _profile_row(row)
        if problem:
            problems.append(problem)
            if len(problems) >= _MAX_LISTED:
                break
    return problems


def _profile_row(row: Any) -> str:
    sid, mag, uz = row[0], row[1], row[2]
    lists = row[3:]
    if all(v is None for v in lists):
        return ""  # complex values not stored for this row
    if any(v is None for v in lists):
        return f"sample {sid[:12]}: some complex profile columns are missing"
    arr = [np.asarray(v, dtype=float) for v in lists]
    if any(a.shape != np.shape(mag) for a in arr):
        return f"sample {sid[:12]}: complex profile lengths differ from profile_magnitude_um"
    if not all(np.all(np.isfinite(a)) for a in arr):
        return f"sample {sid[:12]}: non-finite complex profile"
    scale = max(float(np.max(np.abs(mag), initial=0)), 1e-300)
    total = np.sqrt(sum(a ** 2 for a in arr))
    normal = np.hypot(arr[2], arr[3])  # components r, z, t: z re/im are entries 2 and 3
    if np.max(np.abs(total - mag)) > _RTOL * scale or np.max(np.abs(normal - uz)) > \
            _RTOL * scale:
        return (f"sample {sid[:12]}: complex profile does not give profile_magnitude_um / "
                "profile_uz_um")
    return ""


def _check_sweeps(manifest: Mapping[str, Any], ok: Any) -> list[str]:
    band = np.asarray(manifest["band"].get("frequency_hz") or [], dtype=float)
    grid = manifest.get("profile_grid_mm")
    problems = []
    cols = ["sample_id", "sweep_frequency_hz", "profile_distance_mm", "sweep_error_estimate",
            "sweep_full_solves", *_SWEEP_LISTS]
    for row in ok[cols].itertuples(index=False):
        problem = _sweep_row(row, band, grid)
        if problem:
            problems.append(problem)
            if len(problems) >= _MAX_LISTED:
                break
    return problems


def _sweep_row(row: Any, band: np.ndarray, grid: Any) -> str:
    sid, freq, dist, err, solves = row[:5]
    if freq is None or dist is None:
        return f"sample {sid[:12]}: missing sweep_frequency_hz or profile_distance_mm"
    freq, dist = np.asarray(freq, dtype=float), np.asarray(dist, dtype=float)
    if freq.shape != band.shape or not np.allclose(freq, band, rtol=0, atol=1e-9):
        return f"sample {sid[:12]}: sweep_frequency_hz differs from the manifest's band"
    if grid is not None and (dist.shape != (len(grid),) or
                             not np.allclose(dist, grid, rtol=0, atol=1e-9)):
        return f"sample {sid[:12]}: profile_distance_mm differs from the manifest's grid"
    if not (np.isfinite(err) and err >= 0) or not solves or solves < 1:
        return (f"sample {sid[:12]}: sweep_error_estimate = {err!r}, sweep_full_solves = "
                f"{solves!r}: need a finite estimate >= 0 and at least one solve")
    for name, values in zip(_SWEEP_LISTS, row[5:], strict=True):
        n = freq.size * (dist.size if "_profile_" in name else 1)
        if values is None or len(values) != n:
            return (f"sample {sid[:12]}: {name} holds "
                    f"{'no list' if values is None else len(values)} values, expected {n}")
        if not np.all(np.isfinite(np.asarray(values, dtype=float))):
            return f"sample {sid[:12]}: {name} has non-finite values"
    return ""
