"""``hapticrom play PLAN.json PATTERN.toml --device sim|log|serial:PORT``: render a pattern
on a planned array.

    hapticrom play out/plan.json examples/pattern-sweep.toml --device sim --out out/play

Everything is checked before a device is opened (the plan and its timing, the pattern, the
safety limits and the daily exposure); a bad input exits 2 naming the field, with nothing
written. ``sim`` writes ``field-peak.png`` and ``field.gif``, ``log`` writes
``commands.jsonl``, into ``--out``; ``serial:PORT`` drives the array (docs/protocol.md) with
a heartbeat running, and stops every channel on exit, on error and on Ctrl-C.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from hapticrom.commands._args import number_in
from hapticrom.outputs import check_dir_output, write_dir

__all__ = ["register"]


_positive_ms = number_in(0.0, 3.6e6, "ms")
_fraction = number_in(0.0, 1.0)


def _run(args: argparse.Namespace) -> int:
    from hardware import (
        ExposureMeter,
        Heartbeat,
        SafetyLimits,
        build_schedule,
        load_pattern,
        load_plan,
        open_device,
        parse_device,
    )
    from hardware.safety import check_schedule

    kind, _ = parse_device(args.device)
    if kind != "serial" and not args.out:
        raise ValueError(f"--device {kind} writes files: give --out DIR")
    if args.out:
        check_dir_output("--out", args.out, kind="play", overwrite=args.overwrite,
                         reads=[args.plan, args.pattern])
    plan = load_plan(args.plan)
    schedule = build_schedule(load_pattern(args.pattern), plan)
    base = SafetyLimits()
    limits = SafetyLimits(max_level=plan.timing["overdrive_level"],
                          max_on_s=(args.max_on_ms or base.max_on_s * 1e3) / 1e3,
                          max_duty=args.max_duty or base.max_duty,
                          watchdog_s=(args.watchdog_ms or base.watchdog_s * 1e3) / 1e3)
    check_schedule(list(schedule.segments), limits)
    meter = ExposureMeter(plan.n_sites, state_path=args.exposure_file if kind == "serial"
                          else None)
    amp_m = np.array([s.rendered_um for s in schedule.steps]) * 1e-6
    dur_s = np.array([s.duration_ms for s in schedule.steps]) * 1e-3
    a8 = meter.check(amp_m, schedule.frequency_hz, dur_s)
    err = max(float(np.abs(s.rendered_um - s.target_um).max()) for s in schedule.steps)
    print(f"{len(schedule.steps)} steps, {len(schedule.segments)} segments, "
          f"{schedule.total_ms} ms at {schedule.frequency_hz:g} Hz on {plan.n_sites} channels; "
          f"largest rendering error {err:.3g} um")
    print(f"daily exposure after this pattern: A(8) <= {a8.max():.3g} m/s^2 at the worst site "
          f"(action value {meter.limit:g} m/s^2; ISO 5349-1 Wh weighting, a hand-arm standard "
          "used as the nearest guide)")
    if kind == "serial":
        with open_device(args.device, plan, None, limits, meter) as dev, Heartbeat(dev) as hb:
            dev.play(schedule)
            status = dev.status()
            if hb.error is not None:
                raise hb.error
        print(f"played on {args.device}; device levels now {max(map(abs, status.levels)):g} "
              "at most")
        return 0
    with write_dir("--out", args.out, kind="play", overwrite=args.overwrite,
                   reads=[args.plan, args.pattern]) as tmp:
        with open_device(args.device, plan, tmp, limits) as dev:
            dev.play(schedule)
        names = sorted(p.name for p in tmp.iterdir())  # before the marker is added
    for name in names:
        print(f"wrote {Path(args.out) / name}")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``play`` subcommand."""
    p = subparsers.add_parser("play", help="play a pattern on a planned array (sim, log, "
                              "serial)")
    p.add_argument("plan", help="plan JSON from `hapticrom plan --out` (with its timing)")
    p.add_argument("pattern", help="pattern TOML (see examples/pattern-sweep.toml)")
    p.add_argument("--device", required=True, metavar="sim|log|serial:PORT",
                   help="sim: render the skin field; log: write the commands; serial:PORT: "
                   "drive the array")
    p.add_argument("--out", metavar="DIR", help="output directory (sim, log); an existing one "
                   "is replaced only with --overwrite and only if play wrote it")
    p.add_argument("--overwrite", action="store_true",
                   help="replace the output of an earlier play in --out")
    p.add_argument("--max-on-ms", type=_positive_ms, metavar="MS",
                   help="longest continuous on-time per channel (default 10000)")
    p.add_argument("--max-duty", type=_fraction, metavar="FRACTION",
                   help="largest on-time fraction of any 60 s window (default 0.5)")
    p.add_argument("--watchdog-ms", type=_positive_ms, metavar="MS",
                   help="serial: the heartbeat deadline the host keeps (default 250)")
    p.add_argument("--exposure-file", type=Path, metavar="JSON",
                   help="serial: today's accumulated exposure, read and updated")
    p.set_defaults(func=_run)
