"""SINDy with control against today's envelope-model fit on the same held-out runs: one table.

Issue 39, item 1 (:mod:`studies.envelope_sindy`): today's grey-box model (``models/rom-default``)
is the known part; pysindy identifies the residual dynamics of the FE envelope with the motor
law's speed, its rate and the known mode as the control, by each variant's library and
optimiser, on the training runs of ``datasets/transient``; every model is scored with the card's
metrics on the 56 held-out runs (``sample_index % 4 == 3``).

    python bench/surrogate/envelope_sindy.py [--model models/rom-default]
        [--data datasets/transient] [--variants poly,sr3,vanishing,sindycp] [--json out.json]

pysindy is not a dependency of the project (this measurement removed it); install it to re-run:
``pip install -c constraints.txt "pysindy==2.1.0"``. About 2 minutes on one core.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from threadpoolctl import threadpool_limits

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from studies.envelope_sindy import VARIANTS, run, table  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", default=str(ROOT / "models" / "rom-default"))
    ap.add_argument("--data", nargs="+", default=[str(ROOT / "datasets" / "transient")])
    ap.add_argument("--variants", default=",".join(VARIANTS),
                    help=f"comma-separated, from {', '.join(VARIANTS)}")
    ap.add_argument("--threads", type=int, default=1, help="BLAS threads")
    ap.add_argument("--json", help="write the records (summaries per model) to this file")
    args = ap.parse_args(argv)
    names = [v for v in args.variants.split(",") if v]
    bad = [v for v in names if v not in VARIANTS]
    if bad:
        print(f"--variants {bad[0]!r}: allowed {', '.join(VARIANTS)}", file=sys.stderr)
        return 2
    try:
        import pysindy  # noqa: F401
    except ImportError:
        print("pysindy is not installed (not a dependency of hapticrom): pip install -c "
              "constraints.txt \"pysindy==2.1.0\"", file=sys.stderr)
        return 2
    with threadpool_limits(args.threads):
        records = run(args.model, args.data, names)
    print(table(records))
    if args.json:
        Path(args.json).write_text(json.dumps(records, indent=1, allow_nan=True) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
