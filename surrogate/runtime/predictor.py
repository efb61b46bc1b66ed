"""The run-time predictor: a model directory in, named amplitudes out (numpy + onnxruntime).

    >>> p = load_predictor("models/default-nn")
    >>> out = p.predict({"orientation": ["forward"], "attachment": ["glued"], ...})
    >>> out["center_amplitude_um"], out["profile_um"], out["edge_radius_mm"]

Outputs per row: ``center_amplitude_um``, ``edge_amplitude_um``, ``normalized_edge``,
``profile_um`` (n, m) on ``profile_distance_mm`` (distance from the unit's outer edge [mm]),
``edge_radius_mm`` (the unit's outer radius [mm]) and ``<output>_log_std`` (predictive std of
the natural log of each amplitude output). A model trained on more profiles returns them too,
by the names of its card's ``log_output_columns`` (``NAME[j]`` columns form the (n, m) output
``NAME``), e.g. ``profile_normal_um``, the normal component |u_z| of the skin surface.
Inputs are validated (:class:`PredictorInputError` names the input); out-of-range points raise
unless ``extrapolate=True``, which adds a boolean ``extrapolated`` array instead.

This module must stay importable without torch, scikit-learn, pysindy or the FE solver.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import onnxruntime as ort

from surrogate.runtime.card import CARD_NAME, ModelFileError, read_card, read_model_file
from surrogate.runtime.encoding import (
    InputSpec,
    PredictorInputError,
    compile_specs,
    encode,
    n_features,
    parse_inputs,
)

__all__ = ["ModelFileError", "Predictor", "PredictorInputError", "load_predictor",
           "make_session"]

SCALAR_OUTPUTS = ("center_amplitude_um", "edge_amplitude_um", "normalized_edge")
_ARRAY_COLUMN = re.compile(r"^(.+)\[(\d+)\]$")


def output_layout(columns: list[str], m: int) -> dict[str, slice | int]:
    """The graph's log-output columns by output name: an index for a scalar output, a slice
    of ``m`` columns for an array output ``NAME[0]`` .. ``NAME[m-1]`` (in order, contiguous).
    ValueError for any other layout; the scalar outputs of :data:`SCALAR_OUTPUTS` and
    ``profile_um`` must lead, as every exported graph writes them."""
    out: dict[str, slice | int] = {}
    k = 0
    while k < len(columns):
        match = _ARRAY_COLUMN.match(columns[k])
        name = match.group(1) if match else columns[k]
        if name in out:
            raise ValueError(f"log_output_columns: {name!r} appears twice")
        if not match:
            out[name] = k
            k += 1
            continue
        want = [f"{name}[{j}]" for j in range(m)]
        if columns[k:k + m] != want:
            raise ValueError(f"log_output_columns: {name}[...] must be {m} columns "
                             f"{want[0]} .. {want[-1]} in order")
        out[name] = slice(k, k + m)
        k += m
    if list(out)[:4] != [*SCALAR_OUTPUTS, "profile_um"]:
        raise ValueError(f"log_output_columns must start with {', '.join(SCALAR_OUTPUTS)}, "
                         "profile_um[...]")
    return out
_DTYPES = {"float32": np.float32, "float64": np.float64}


def make_session(model: bytes | str | Path, threads: int = 1) -> ort.InferenceSession:
    """An onnxruntime CPU session tuned for small calls from one thread: ``threads`` intra-op
    threads, no inter-op pool, no busy-wait spinning between calls."""
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = threads
    opts.inter_op_num_threads = 1
    opts.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
    opts.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
    opts.add_session_config_entry("session.intra_op.allow_spinning", "0")
    opts.log_severity_level = 4  # a failure is raised (and named by the loader), not logged
    src = model if isinstance(model, bytes) else str(model)
    return ort.InferenceSession(src, sess_options=opts, providers=["CPUExecutionProvider"])


class EdgeRadius:
    """The unit's outer radius [mm], an exact function of the discrete design inputs stored
    in the card as a table (every combination seen in training -> its radius)."""

    def __init__(self, rule: dict[str, Any], specs: list[InputSpec]) -> None:
        names = [s.name for s in specs]
        if rule.get("method") != "table":
            raise ModelFileError("edge_radius", f"edge_radius method {rule.get('method')!r} "
                                 "unknown (expected 'table')")
        self.columns = [names.index(n) for n in rule["inputs"]]
        self.inputs = list(rule["inputs"])
        self.keys = np.asarray(rule["keys"], dtype=float).reshape(-1, len(self.columns))
        self.values = np.asarray(rule["values_mm"], dtype=float)

    def __call__(self, codes: np.ndarray) -> np.ndarray:
        sub = codes[:, self.columns]
        match = np.all(sub[:, None, :] == self.keys[None, :, :], axis=2)
        found = match.any(axis=1)
        if not found.all():
            i = int(np.argmin(found))
            combo = dict(zip(self.inputs, sub[i].tolist(), strict=True))
            raise PredictorInputError(self.inputs[0] if self.inputs else "X",
                                      f"row {i}: the combination {combo} of structural inputs "
                                      "was never trained")
        return self.values[np.argmax(match, axis=1)]


class Predictor:
    """A loaded model: validated inputs in, named outputs out. Build with
    :func:`load_predictor`. The ONNX session is made once, with one thread."""

    def __init__(self, card: dict[str, Any], session: ort.InferenceSession) -> None:
        self.card = card
        self.specs = [InputSpec.from_dict(d) for d in card["inputs"]]
        self.input_names: tuple[str, ...] = tuple(s.name for s in self.specs)
        self.input_ranges: dict[str, tuple[float, float]] = {s.name: s.range
                                                             for s in self.specs}
        self.profile_distance_mm = np.asarray(card["profile_distance_mm"], dtype=float)
        m = self.profile_distance_mm.size
        self._layout = output_layout(list(card.get("log_output_columns") or
                                          [*SCALAR_OUTPUTS, *(f"profile_um[{j}]"
                                                              for j in range(m))]), m)
        self.n_log_outputs = sum(1 if isinstance(v, int) else m for v in self._layout.values())
        self.output_names: tuple[str, ...] = (*self._layout, "edge_radius_mm")
        self.kind = str(card.get("kind", ""))
        self.session = session
        self._dtype = _DTYPES[card["graph"]["dtype"]]
        self._edge = EdgeRadius(card["edge_radius"], self.specs)
        self._plan = compile_specs(self.specs)

    def features(self, X: Any, *, extrapolate: bool = False) -> tuple[np.ndarray, np.ndarray,
                                                                       np.ndarray]:
        """(codes, encoded features in the graph's dtype, extrapolated mask)."""
        codes, outside = parse_inputs(X, self.specs, extrapolate=extrapolate, plan=self._plan)
        return codes, encode(codes, self.specs, plan=self._plan).astype(self._dtype), outside

    def predict(self, X: Any, *, extrapolate: bool = False) -> dict[str, np.ndarray]:
        """Predict every output for design points ``X`` (see the module docstring)."""
        codes, feats, outside = self.features(X, extrapolate=extrapolate)
        log_mean, log_std = self.session.run(["log_mean", "log_std"], {"x": feats})
        log_mean, log_std = log_mean.astype(float), log_std.astype(float)
        out: dict[str, np.ndarray] = {}
        for name, cols in self._layout.items():
            out[name] = np.exp(log_mean[:, cols])
            out[f"{name}_log_std"] = log_std[:, cols]
        out["edge_radius_mm"] = self._edge(codes)
        if extrapolate:
            out["extrapolated"] = outside
        return out


def _session(path: Path, name: str, data: bytes) -> ort.InferenceSession:
    """An onnxruntime session of the graph bytes ``data`` (never a path: a graph's external
    data or custom-op library cannot be fetched from elsewhere); any failure is a refusal
    naming the file."""
    try:
        return make_session(data)
    except Exception as err:  # onnxruntime raises its own classes (InvalidProtobuf, Fail, ...)
        text = str(err).strip().splitlines()[0][:300] if str(err).strip() else ""
        raise ModelFileError(name, f"{path / name}: not an ONNX graph this runtime can run "
                             f"(check: graph; {type(err).__name__}: {text})") from None


def _check_graph(path: Path, name: str, card: dict[str, Any],
                 session: ort.InferenceSession, width: int, n_out: int) -> None:
    """The graph's contract: one input ``x`` (batch, width) of the card's dtype and outputs
    ``log_mean`` and ``log_std`` of (batch, n_out), checked on one row."""
    where = f"{path / name}: the graph does not match the card (check: graph contract; "
    inputs = session.get_inputs()
    if [i.name for i in inputs] != ["x"]:
        raise ModelFileError(name, where + f"inputs {[i.name for i in inputs]}, expected "
                             "['x'])")
    outs = {o.name for o in session.get_outputs()}
    if not {"log_mean", "log_std"} <= outs:
        raise ModelFileError(name, where + f"outputs {sorted(outs)}, expected log_mean and "
                             "log_std)")
    try:
        mean, std = session.run(["log_mean", "log_std"],
                                {"x": np.zeros((1, width), _DTYPES[card["graph"]["dtype"]])})
    except Exception as err:
        raise ModelFileError(name, where + f"one row of {width} features fails: "
                             f"{type(err).__name__})") from None
    for label, arr in (("log_mean", mean), ("log_std", std)):
        if np.shape(arr) != (1, n_out):
            raise ModelFileError(name, where + f"{label} has shape {np.shape(arr)} for one "
                                 f"row, expected (1, {n_out}))")


def load_predictor(path: str | Path) -> Predictor:
    """Load ``models/NAME/`` as a :class:`Predictor`, after verifying the directory as a whole
    (:func:`surrogate.runtime.card.verify_model_dir`) and the graph against the card; any
    failure is a :class:`ModelFileError` naming the file and the check."""
    root = Path(path)
    card = read_card(root)
    if "graph" not in card:  # the steady-state contract, whatever the kind's name
        raise ModelFileError("kind", f"{root / CARD_NAME}: a {card.get('kind')!r} model, not "
                             "a steady-state predictor (no ONNX graph)")
    graph = card["graph"]
    if not isinstance(graph, dict) or not isinstance(graph.get("dtype"), str) \
            or graph["dtype"] not in _DTYPES:
        raise ModelFileError("graph", f"{root / CARD_NAME}: graph.dtype must be one of "
                             f"{sorted(_DTYPES)} (check: keys)")
    name = graph["file"]
    session = _session(root, name, read_model_file(root, card, name))
    try:
        predictor = Predictor(card, session)
        width = n_features(predictor.specs)
    except ModelFileError:
        raise
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as err:
        raise ModelFileError(CARD_NAME, f"{root / CARD_NAME}: malformed card "
                             f"(check: card values; {type(err).__name__}: {err})") from None
    _check_graph(root, name, card, session, width, predictor.n_log_outputs)
    return predictor
