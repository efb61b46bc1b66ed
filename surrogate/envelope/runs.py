"""FE transient runs for the envelope model's fit (``surrogate.envelope.fit``): the rows of datasets
generated from ``datasets/spaces/transient.toml`` read, their drive rebuilt and their
displacement histories demodulated with the rotor angle into envelopes. Nothing here imports
the solver: it reads stored rows only.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.signal import hilbert

import motorlaw
from surrogate.data.store import Store
from surrogate.runtime.rom import MOTOR_INPUTS, POINTS

__all__ = ["Run", "complex_envelopes", "load_runs", "run_from_row", "schedule_volts"]


@dataclass(frozen=True)
class Run:
    """One transient FE run.

    Attributes:
        t: (nt,) times, s. volts: (nt,) drive held from each time, V.
        omega: (nt,) motor speed, rad/s (exact). env: (2, nt) FE envelopes (center, edge), um.
        design: the envelope model's ``input_names`` -> value. sample_index: dataset row.
        on_time_s: first time the drive drops to <= 0 V (end of the first burst), s.
    """

    t: NDArray
    volts: NDArray
    omega: NDArray
    env: NDArray
    design: dict[str, Any]
    sample_index: int
    on_time_s: float


def complex_envelopes(u: NDArray, phi: NDArray) -> NDArray:
    """Complex envelopes analytic(u_c) e^{-i phi} of (3, nt) component histories.

    Before the FFT-based Hilbert transform the record is extended at its start by even
    reflection and at its end by zeros, which keeps the end artefacts within about a period.
    The run starts from rest (u = du/dt = 0), so the even extension is smooth at t = 0 and
    its Hilbert transform vanishes there: the envelope starts at 0, as the model's does. An
    odd reflection does not: the first slow cycles of a spin-up (a few hertz) in a component
    in sine phase with the rotor (u_theta on the theta = 0 meridian) give a spurious envelope
    of 10-15 % of the steady level at t = 0 (measured:
    ``bench/surrogate/transient_rise_check.py``)."""
    u = np.asarray(u, dtype=float)
    head = u[:, 1:][:, ::-1]
    tail = np.zeros((u.shape[0], u.shape[1] - 1))
    ext = np.concatenate([head, u, tail], axis=1)
    a = hilbert(ext, axis=1)[:, head.shape[1]: head.shape[1] + u.shape[1]]
    return a * np.exp(-1j * phi)


def schedule_volts(t: NDArray, schedule_ms: Sequence[Sequence[float]]) -> NDArray:
    """Voltage held at each time (s) of a [[t_ms, V], ...] step schedule."""
    starts = np.array([s[0] for s in schedule_ms]) * 1e-3
    levels = np.array([s[1] for s in schedule_ms], dtype=float)
    return levels[np.searchsorted(starts, t + 1e-12, side="right") - 1]


def run_from_row(row: Mapping[str, Any], design_names: Sequence[str]) -> tuple[Run, dict]:
    """A :class:`Run` and the motor law's fixed parameters of one dataset row."""
    scene = json.loads(row["scene_json"])
    kind = scene.get("load", {}).get("kind")
    if kind != motorlaw.SpeedLaw.kind:  # the model's form follows the ERM's speed law
        raise ValueError(f"--data: sample {row.get('sample_index')} drives load.kind = "
                         f"{kind!r}; the envelope model is fitted on {motorlaw.SpeedLaw.title} "
                         f"transients (load.kind = {motorlaw.SpeedLaw.kind!r})")
    m = scene["unit"]["motor"]
    schedule = scene["analysis"]["voltage_schedule"]
    law = motorlaw.SpeedLaw(
        rated_voltage_V=float(m["rated_voltage_V"]),
        rated_frequency_hz=float(m["rated_frequency_hz"]),
        start_voltage_V=float(m["start_voltage_V"]),
        tau_spinup_s=float(m["tau_spinup_ms"]) * 1e-3,
        tau_spindown_s=float(m["tau_spindown_ms"]) * 1e-3,
        max_voltage_V=max(motorlaw.DEFAULTS["max_voltage_V"],
                          max(abs(v) for _, v in schedule)))
    t = np.asarray(row["history_t_s"], dtype=float)
    steps = motorlaw.VoltageSchedule(tuple((a * 1e-3, b) for a, b in schedule))
    omega, phi = motorlaw.speed_and_phase(law, steps, t)
    env = np.stack([np.sqrt(np.sum(np.abs(complex_envelopes(
        np.stack([np.asarray(c, dtype=float) for c in row[f"history_{p}_um"]]), phi)) ** 2,
        axis=0)) for p in POINTS])
    design = {k: row[k] for k in design_names}
    design.update({k: float(m[k]) for k in MOTOR_INPUTS})
    off = [s[0] * 1e-3 for s in schedule if s[1] <= 0.0]
    fixed = {k: getattr(law, k) for k in ("rated_voltage_V", "rated_frequency_hz",
                                          "start_voltage_V")}
    return Run(t, schedule_volts(t, schedule), omega, env, design, int(row["sample_index"]),
               off[0] if off else float(t[-1])), fixed


def load_runs(paths: Sequence[str | Path], design_names: Sequence[str]
              ) -> tuple[list[Run], dict[str, float], list[str]]:
    """Successful transient runs of the datasets, the common fixed motor parameters and the
    sha256 of each manifest. Raises ValueError (naming --data) for a dataset without them."""
    runs: list[Run] = []
    fixed: dict[str, float] | None = None
    hashes = []
    for path in paths:
        manifest = Path(path) / "_manifest.json"
        if not manifest.is_file():
            raise ValueError(f"--data: {path} is not a dataset (no _manifest.json)")
        hashes.append(hashlib.sha256(manifest.read_bytes()).hexdigest())
        df = Store.open(path).read()  # the manifest's parts, checked against their digests
        missing = [c for c in ("history_center_um", *design_names) if c not in df]
        if missing:
            raise ValueError(f"--data: {path} has no column {missing[0]!r} (generate it from "
                             "datasets/spaces/transient.toml)")
        df = df[(df["status"] == "ok") & df["history_center_um"].notna()]
        for row in df.to_dict("records"):
            run, f = run_from_row(row, design_names)
            if fixed is not None and f != fixed:
                raise ValueError(f"--data: sample {run.sample_index} of {path} has another "
                                 f"motor law ({f}) than the first ({fixed})")
            fixed = f
            runs.append(run)
    if fixed is None:
        raise ValueError(f"--data: no successful transient run in {list(map(str, paths))}")
    return sorted(runs, key=lambda r: r.sample_index), fixed, hashes


# --------------------------------------------------------------------------- fitting
