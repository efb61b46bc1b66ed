"""Mutation campaign over model directories: alter copies of the shipped models every way a
file can be altered and count what the command line does with each.

    .venv/bin/python bench/runtime/model_mutations.py [--n 300] [--seed 0]

Each mutation is applied to a fresh copy of models/{gp,nn,rom}-default, then the copy is used
as a user would: ``hapticrom models show DIR`` and, for a steady model, ``hapticrom predict``
at a valid design (a ROM: ``load_envelope_model(DIR).simulate`` on a short drive). Outcomes:

- refused: exit 2, the message names a file of the model (card.json or a listed file);
- silently accepted: an alteration that was NOT re-sealed and was used (must be 0);
- traceback: exit 1, a Python traceback, or an exception escaping (must be 0);
- unnamed refusal: exit 2 without a file name in the message (must be 0);
- wrote: a file appeared or changed beside the model while it was read (must be 0);
- re-sealed, consistent: an edit whose digests were all recomputed and which loads; integrity
  cannot tell it from a model trained that way (a signature could), so it is counted apart.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import io
import json
import os
import random
import shutil
import sys
import tempfile
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from hapticrom.cli import main  # noqa: E402
from surrogate.runtime import (  # noqa: E402
    ModelFileError,
    RomBlowUpError,
    RomInputError,
    load_envelope_model,
)
from surrogate.runtime.card import seal_card  # noqa: E402

KINDS = ("gp", "nn", "rom")


def _card(d: Path) -> dict:
    return json.loads((d / "card.json").read_text())


def _write(d: Path, card: dict) -> None:
    (d / "card.json").write_text(json.dumps(card, indent=1) + "\n")


def _reseal(d: Path, card: dict | None = None) -> None:
    card = _card(d) if card is None else card
    if isinstance(card.get("files"), dict):
        card["files"] = {n: (hashlib.sha256((d / n).read_bytes()).hexdigest()
                             if (d / n).is_file() and "/" not in n and n not in ("", ".", "..")
                             else v) for n, v in card["files"].items()}
    _write(d, seal_card(card))


def _leaves(obj, path=()):
    yield path, obj
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _leaves(v, (*path, k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _leaves(v, (*path, i))


def _value(rng: random.Random):
    return rng.choice([None, True, 0, -1, 1e308, -1e-308, 7, 0.5, "", "x", "../x", [], {},
                       [1, 2], {"a": 1}, "model.onnx", 1e7, -1e7])


def _first_file(d: Path) -> str:
    return next(iter(_card(d)["files"]))


# ------------------------------------------------------------------ mutations (name -> fn)
# each returns True when the alteration was re-sealed (every digest recomputed)


def flip_byte(d: Path, rng: random.Random, reseal: bool = False) -> bool:
    name = _first_file(d)
    data = bytearray((d / name).read_bytes())
    data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
    (d / name).write_bytes(bytes(data))
    if reseal:
        _reseal(d)
    return reseal


def edit_card(d: Path, rng: random.Random, reseal: bool = False) -> bool:
    card = _card(d)
    paths = [p for p, _ in _leaves(card) if p and p[0] != "card_sha256"]
    path = rng.choice(paths)
    obj = card
    for k in path[:-1]:
        obj = obj[k]
    new = _value(rng)
    if obj[path[-1]] == new:
        new = [new]
    obj[path[-1]] = new
    if reseal:
        _reseal(d, card)
    else:
        _write(d, card)
    return reseal


def delete_key(d: Path, rng: random.Random) -> bool:
    card = _card(d)
    del card[rng.choice([k for k in card if k != "card_sha256"])]
    _reseal(d, card)
    return True


def escape_name(d: Path, rng: random.Random) -> bool:
    card = _card(d)
    old = _first_file(d)
    name = rng.choice(["../_evil/" + old, str(d.parent / "_evil" / old), "sub/" + old, "..",
                       "card.json", ""])
    evil = d.parent / "_evil"
    evil.mkdir(exist_ok=True)
    shutil.copy(d / old, evil / old)
    card["files"] = {name: card["files"][old]}
    if card.get("kind") == "rom":
        card["coefficients"] = name
    else:
        card["graph"]["file"] = name
    _reseal(d, card)
    return True


def symlink_file(d: Path, rng: random.Random) -> bool:
    name = rng.choice([_first_file(d), "card.json"])
    outside = d.parent / f"outside-{name}"
    shutil.copy(d / name, outside)
    (d / name).unlink()
    os.symlink(outside, d / name)
    return False


def stray_entry(d: Path, rng: random.Random) -> bool:
    kind = rng.choice(["file", "dir", "symlink"])
    target = d / rng.choice(["notes.txt", "extra.onnx", ".hidden"])
    if kind == "file":
        target.write_text("x")
    elif kind == "dir":
        target.mkdir()
    else:
        os.symlink(d / _first_file(d), target)
    return False


def damage_card(d: Path, rng: random.Random) -> bool:
    raw = (d / "card.json").read_bytes()
    how = rng.choice(["truncate", "junk", "bom-bytes", "deep", "not-object", "empty"])
    if how == "truncate":
        raw = raw[:rng.randrange(len(raw))]
    elif how == "junk":
        raw = raw + bytes(rng.randrange(256) for _ in range(8))
    elif how == "bom-bytes":
        raw = b"\xff\xfe" + raw
    elif how == "deep":
        raw = raw.rstrip()[:-1] + b', "x": ' + b"[" * 1000 + b"]" * 1000 + b"}"
    elif how == "not-object":
        raw = b"[1, 2]"
    else:
        raw = b""
    (d / "card.json").write_bytes(raw)
    return False


def replace_graph(d: Path, rng: random.Random) -> bool:
    name = _first_file(d)
    (d / name).write_bytes(rng.choice([b"", b"\x08\x07" * 50, os.urandom(200),
                                       b"{not json", b'{"format": 3}']))
    _reseal(d)
    return True


MUTATIONS = {
    "flip byte": lambda d, r: flip_byte(d, r),
    "flip byte, re-sealed": lambda d, r: flip_byte(d, r, True),
    "edit card value": lambda d, r: edit_card(d, r),
    "edit card value, re-sealed": lambda d, r: edit_card(d, r, True),
    "delete card key, re-sealed": delete_key,
    "named file leaves the directory, re-sealed": escape_name,
    "symlink": symlink_file,
    "stray entry": stray_entry,
    "damaged card file": damage_card,
    "replaced model file, re-sealed": replace_graph,
}


def _tree(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.is_file() and not p.is_symlink()}


def _point(card: dict) -> list[str]:
    args = []
    for s in card["inputs"]:
        v = s["choices"][0] if s.get("choices") else 0.5 * (s["low"] + s["high"])
        args += ["--set", f"{s['name']}={2 if s['name'] == 'n_rings' else v}"]
    return args


def _run(argv: list[str]) -> tuple[int, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue() + err.getvalue()


def _use(d: Path, kind: str, point: list[str]) -> tuple[int, str, bool]:
    """Exit code and text of using model ``d`` as a user would, and whether it loaded (a
    refusal after loading is about the design point, not the model)."""
    code, text = _run(["models", "show", str(d)])
    if code != 0:
        return code, text, False
    if kind != "rom":
        return (*_run(["predict", str(d), *point]), True)
    try:
        model = load_envelope_model(d)
        design = {k: (v[0] if isinstance(v[0], str) else 0.5 * (v[0] + v[1]))
                  for k, v in model.input_ranges.items()}
        model.simulate([0.0, 0.01, 0.02], [3.0, 3.0, 0.0], design)
    except (ModelFileError, RomInputError, RomBlowUpError) as err:
        return 2, str(err), True
    return 0, "", True


def _outcome(code: int, text: str, loaded: bool, resealed: bool, named: list[str]) -> str:
    if code == 1 or "Traceback" in text:
        return "traceback"
    if code == 0 or loaded:
        return "re-sealed, consistent" if resealed else "silently accepted"
    return "refused" if any(w in text for w in named) else "unnamed refusal"


def campaign(n: int, seed: int) -> tuple[Counter, dict[str, Counter]]:
    """Totals and the outcomes of each mutation over ``n`` mutated copies."""
    rng = random.Random(seed)
    counts: Counter = Counter()
    points = {k: _point(_card(ROOT / "models" / f"{k}-default")) for k in ("gp", "nn")}
    names = list(MUTATIONS)
    by_mutation: dict[str, Counter] = {m: Counter() for m in names}
    for i in range(n):
        kind, mutation = KINDS[i % 3], names[(i // 3) % len(names)]
        with tempfile.TemporaryDirectory(prefix="mutation-") as tmp:
            d = Path(tmp) / "m"
            shutil.copytree(ROOT / "models" / f"{kind}-default", d)
            before_files = _tree(d)
            resealed = MUTATIONS[mutation](d, rng)
            if _tree(d) == before_files and not any(p.is_symlink() or p.is_dir()
                                                    for p in d.iterdir()):
                counts["unchanged (skipped)"] += 1
                continue
            named = ["card.json", "graph.file", "coefficients", "listed file",
                     *(p.name for p in d.iterdir())]
            with contextlib.suppress(Exception):
                named += [n for n in json.loads((d / "card.json").read_text())["files"] if n]
            before = _tree(Path(tmp))
            try:
                code, text, loaded = _use(d, kind, points.get(kind, []))
            except Exception as exc:  # escaped the command line: a crash
                code, text, loaded = 1, f"Traceback {type(exc).__name__}: {exc}", False
            counts["mutations"] += 1
            if _tree(Path(tmp)) != before:
                counts["wrote"] += 1
            outcome = _outcome(code, text, loaded, resealed, named)
            counts[outcome] += 1
            by_mutation[mutation][outcome] += 1
            if outcome in ("traceback", "silently accepted", "unnamed refusal"):
                print(f"{outcome}: {kind} {mutation}: {text.strip()[-300:]}")
    return counts, by_mutation


def run() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=300, help="mutations (default 300)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    counts, by_mutation = campaign(args.n, args.seed)
    for mutation, c in by_mutation.items():
        print(f"  {mutation:44s} " + ", ".join(f"{k} {v}" for k, v in sorted(c.items())))
    for key in ("mutations", "refused", "re-sealed, consistent", "silently accepted",
                "traceback", "unnamed refusal", "wrote", "unchanged (skipped)"):
        print(f"{key:24s} {counts.get(key, 0)}")
    bad = counts["silently accepted"] + counts["traceback"] + counts["unnamed refusal"] \
        + counts["wrote"]
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(run())
