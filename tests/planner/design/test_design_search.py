"""The optimisers find the known optimum of a synthetic objective on the design space, and a
search is deterministic for a seed (on the real objective)."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from planner.design.evaluate import Evaluation
from planner.design.request import design_request_from_dict
from planner.design.run import design, model_domain, pareto_front
from planner.design.search import run_search
from planner.design.space import DesignSpace


class Synthetic:
    """An evaluator of a known function (distinct designs counted, as the real one does)."""

    def __init__(self, space: DesignSpace, score) -> None:
        self.space, self.score = space, score
        self.seen: dict[tuple, Evaluation] = {}
        self.history: list[Evaluation] = []
        self.batches = 0
        self.wall_s = 0.0

    @property
    def unique(self) -> int:
        return len(self.history)

    def __call__(self, batch):
        self.batches += 1
        out = []
        for x in batch:
            k = self.space.key(x)
            if k not in self.seen:
                self.seen[k] = Evaluation(len(self.history), "", x, None, self.score(x))
                self.history.append(self.seen[k])
            out.append(self.seen[k])
        return out


def _space(request_dict, **space) -> DesignSpace:
    request_dict["space"] = space
    req = design_request_from_dict(request_dict)
    return DesignSpace(req.space, model_domain(req.layout))


TARGET = {"orientation": "reverse", "attachment": "glued", "n_rings": 3,
          "ring_1_E_kPa": 95.0, "ring_2_E_kPa": 260.0, "ring_3_E_kPa": 142.0}


def _mismatch(x: dict, target: dict = TARGET) -> float:
    """10 at ``target`` only; every differing input adds (the ring count the most)."""
    d = 3.0 * abs(x["n_rings"] - target["n_rings"])
    d += sum(x[k] != target[k] for k in ("orientation", "attachment"))
    d += sum(abs(math.log(x[f"ring_{k}_E_kPa"] / target[f"ring_{k}_E_kPa"]))
             for k in (1, 2, 3) if k <= min(x["n_rings"], target["n_rings"]))
    return 10.0 + d


@pytest.mark.parametrize("method", ["de", "cmaes"])
def test_optimiser_finds_the_catalogue_optimum(request_dict, method):
    space = _space(request_dict, catalogue=["A", "B", "C", "D"])  # 2 x 2 x 85 = 340 designs
    ev = Synthetic(space, _mismatch)
    run_search(space, ev, method, 300, 16, seed=3)
    best = min(ev.history, key=lambda e: e.score)
    assert best.score == 10.0
    assert ev.unique <= 300 + 16 * 3  # the budget (a last batch may pass it)


def test_tpe_finds_the_optimum_of_a_small_space(request_dict):
    space = _space(request_dict, catalogue=["A", "B", "C", "D"], n_rings=[0, 1, 2])
    target = {**TARGET, "n_rings": 2}  # one of 2 x 2 x (1 + 4 + 16) = 84 designs
    ev = Synthetic(space, lambda x: _mismatch(x, target))
    run_search(space, ev, "tpe", 30, 8, seed=0)
    assert min(e.score for e in ev.history) == 10.0
    assert ev.unique < 84


def test_de_finds_a_continuous_optimum(request_dict):
    space = _space(request_dict, materials="continuous", n_rings=[1], orientations=["forward"],
                   attachments=["glued"])
    ev = Synthetic(space, lambda x: abs(math.log10(x["ring_1_E_kPa"] / 300.0))
                   + abs(x["ring_density_kg_m3"] - 1050.0) / 100.0)
    run_search(space, ev, "de", 400, 16, seed=0)
    best = min(ev.history, key=lambda e: e.score).inputs
    assert best["ring_1_E_kPa"] == pytest.approx(300.0, rel=0.03)
    assert best["ring_density_kg_m3"] == pytest.approx(1050.0, abs=3.0)


def test_grid_is_every_design_once(request_dict):
    space = _space(request_dict, catalogue=["A", "D"], n_rings=[0, 2])
    designs = space.grid()
    assert len(designs) == 2 * 2 * (1 + 4)
    assert len({space.key(x) for x in designs}) == len(designs)


def test_search_is_deterministic_for_a_seed(request_dict):
    request_dict["space"] = {"catalogue": ["A", "C", "D"], "n_rings": [0, 1, 2]}
    request_dict["search"] = {"budget": 24, "batch": 8}
    request_dict["reference"] = {"scenes": []}
    req = design_request_from_dict(request_dict)
    runs = [design(req, seed=5) for _ in range(2)]
    a, b = ([(e.name, e.score, e.frequency_hz) for e in r.history] for r in runs)
    assert a == b and len(a) >= 24
    assert runs[0].winner.name == runs[1].winner.name
    other = design(replace(req), seed=6)
    assert [e.name for e in other.history] != [e[0] for e in a]  # the seed matters


def test_pareto_front_is_non_dominated():
    evs = [Evaluation(i, str(i), {}, None, p, 150.0, p, p, p, c)
           for i, (p, c) in enumerate([(10, 5), (12, 4), (11, 8), (20, 9), (15, 8)])]
    assert pareto_front(evs) == [0, 2, 3]


def test_finalists_differ_beyond_near_copies():
    from planner.design.run import distinct

    a = {"orientation": "reverse", "attachment": "pogo", "n_rings": 1, "ring_1_E_kPa": 95.0,
         "ring_2_E_kPa": 95.0, "ring_3_E_kPa": 95.0, "ring_density_kg_m3": 1040.0,
         "ring_nu": 0.49, "ring_loss_factor": 0.1}
    assert not distinct(a, {**a, "ring_1_E_kPa": 96.0, "ring_2_E_kPa": 500.0})  # ring 2 unused
    assert distinct(a, {**a, "ring_1_E_kPa": 118.0})  # the catalogue's next silicone
    assert distinct(a, {**a, "attachment": "glued"})
    assert distinct(a, {**a, "n_rings": 2})
