"""``hapticrom play PLAN.json PATTERN.toml --device sim|log|serial:PORT``: render a pattern
on a planned array.

    hapticrom play out/plan.json examples/pattern-sweep.toml --device sim --out out/play

The plan is untrusted input: checked against its schema, every number against its physical
range and its digest (an edited plan plays only with ``--allow-edited-plan``, recorded). The
drive limits never come from it: the device's own (STATUS), then the actuator's rated values,
then the user's (flags or ``--limits FILE``), each only able to lower the one before
(:mod:`hardware.limits`). A plan or pattern asking beyond them is refused before anything is
sent, naming the field, the value and the limit (exit 2); the ``log`` device and the serial
session record keep the refusal. ``sim`` writes ``field-peak.png`` and ``field.gif``, ``log``
writes ``commands.jsonl`` into ``--out``; ``serial:PORT`` drives the array (docs/protocol.md)
with a heartbeat, stops every channel on exit, on error and on Ctrl-C, and with ``--out`` keeps
a ``session-*.jsonl`` record. A schedule the device cut short (watchdog, on-time stop, lost
link, refusal while playing) is reported step by step, exit 1.
"""

from __future__ import annotations

import argparse
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from fieldspec import FieldError
from hapticrom.commands._args import number_in
from hapticrom.documents import schema
from hapticrom.outputs import check_dir_output, check_not_input, write_dir

__all__ = ["register"]


_positive_ms = number_in(0.0, 3.6e6, "ms")
_fraction = number_in(0.0, 1.0)
_level = number_in(0.0, 8.0)
_action = number_in(0.0, 5.0, "m/s^2")

#: option -> SafetyLimits field and factor (the option's unit to the field's)
_FLAGS = {"max_level": ("--max-level", "max_level", 1.0),
          "max_on_ms": ("--max-on-ms", "max_on_s", 1e-3),
          "max_duty": ("--max-duty", "max_duty", 1.0),
          "watchdog_ms": ("--watchdog-ms", "watchdog_s", 1e-3),
          "exposure_action": ("--exposure-action", "exposure_limit", 1.0)}


def _user_limits(args: argparse.Namespace) -> list[tuple[str, float, str]]:
    """The user's settings, the limits file's first, then the flags'."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from hardware.limits import USER_KEYS, load_user_limits

    out = []
    if args.limits:
        for key, v in load_user_limits(args.limits).items():
            name, factor = USER_KEYS[key]
            out.append((name, v * factor, f"{args.limits}: limits.{key} = {v:g}"))
    for attr, (flag, name, factor) in _FLAGS.items():
        v = getattr(args, attr)
        if v is not None:
            out.append((name, v * factor, f"{flag} {v:g}"))
    return out


def _prepare(dev: Any, args: argparse.Namespace, plan: Any, schedule: Any,
             meter: Any) -> None:
    """Integrity, limits, preflight, exposure (raises on a refusal); nothing is sent."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from hardware import PlanFileError
    from hardware.limits import preflight, rating_of, resolve_limits

    rec = plan.record
    dev.note("plan", path=str(args.plan), integrity=rec.status, recorded_sha256=rec.recorded,
             actual_sha256=rec.actual,
             allowed_by="--allow-edited-plan" if not rec.trusted and args.allow_edited_plan
             else None)
    if not rec.trusted:
        if not args.allow_edited_plan:
            raise PlanFileError("plan_sha256", f"{args.plan}: the plan is {rec.describe()}; "
                                "re-plan with `hapticrom plan`, or play it as it is with "
                                "--allow-edited-plan (recorded in the log)")
        print(f"warning: playing a plan that is {rec.describe()} (--allow-edited-plan)",
              file=sys.stderr)
    resolved = resolve_limits(plan.frequency_hz, dev.reported_limits(), rating_of(plan),
                              user=_user_limits(args))
    dev.set_limits(resolved.limits)
    dev.note("limits", **resolved.to_dict())
    preflight(plan, schedule, resolved)
    meter.limit = resolved.limits.exposure_limit
    amp_m = np.array([s.rendered_um for s in schedule.steps]) * 1e-6
    dur_s = np.array([s.duration_ms for s in schedule.steps]) * 1e-3
    a8 = meter.check(amp_m, schedule.frequency_hz, dur_s)
    print(f"limits: level {resolved.describe('max_level')}")
    print(f"daily exposure after this pattern: A(8) <= {a8.max():.3g} m/s^2 at the worst site "
          f"(action value {meter.limit:g} m/s^2; ISO 5349-1 Wh weighting, a hand-arm standard "
          "used as the nearest guide)")


def _play(kind: Any, dev: Any, args: argparse.Namespace, plan: Any, schedule: Any,
          meter: Any) -> BaseException | None:
    """Run the session on ``dev``; a refusal or an interruption is recorded on the device and
    returned (the caller decides what is kept); anything else propagates."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from hardware import Heartbeat
    from hardware.device import PlaybackInterrupted

    try:
        _prepare(dev, args, plan, schedule, meter)
        if kind.live:  # a live array stops itself if the host goes quiet
            with Heartbeat(dev):
                dev.play(schedule)
        else:
            dev.play(schedule)
    except FieldError as err:  # refused (plan, limits, exposure, the device's NAK)
        info = err.to_dict() if hasattr(err, "to_dict") else {"field": err.field,
                                                                "message": str(err)}
        dev.note("refused", **info)
        return err
    except PlaybackInterrupted as err:
        dev.note("interrupted", **err.report)
        return err
    return None


def _live(kind: Any, args: argparse.Namespace, plan: Any, schedule: Any, meter: Any,
          record: Any) -> BaseException | None:
    """Play on a live array (``serial:PORT``): the outcome of :func:`_play`, or the link lost
    while stopping after the pattern (a PlaybackInterrupted too: the pattern had been
    played)."""
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from hardware import DeviceError, open_device
    from hardware.device import PlaybackInterrupted
    from hardware.playback import playback_report

    outcome: BaseException | None = None
    played = False
    dev = open_device(args.device, plan, None, None, meter, record=record)
    try:
        with dev:
            outcome = _play(kind, dev, args, plan, schedule, meter)
            played = outcome is None
            if played:
                level = max(map(abs, dev.status().levels))
                print(f"played on {args.device}; device levels now {level:g} at most")
    except DeviceError as err:  # the link went away: while starting, stopping or closing
        if outcome is not None:
            return outcome  # already reported; the device's watchdog stops the array
        when = ", after the whole pattern was played" if played else ""
        return PlaybackInterrupted(playback_report(
            schedule, schedule.total_ms if played else 0.0, "link", f"{err}{when}"))
    return outcome


def _run(args: argparse.Namespace) -> int:
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from hardware import ExposureMeter, build_schedule, load_pattern, load_plan, open_device
    from hardware.backends import device_kind

    kind, _ = device_kind(args.device)
    if kind.writes_files and not args.out:
        raise ValueError(f"--device {kind.name} writes files: give --out DIR")
    if args.out and kind.live:  # a folder of session records, added to
        check_not_input("--out", args.out, [args.plan, args.pattern])
    elif args.out:
        check_dir_output("--out", args.out, kind="play", overwrite=args.overwrite,
                         reads=[args.plan, args.pattern])
    plan = load_plan(args.plan, schema("plan"))
    schedule = build_schedule(load_pattern(args.pattern), plan)
    _user_limits(args)  # a bad limits file is refused before any device is opened
    meter = ExposureMeter(plan.n_sites, state_path=args.exposure_file if kind.live else None)
    err = max(float(np.abs(s.rendered_um - s.target_um).max()) for s in schedule.steps)
    print(f"{len(schedule.steps)} steps, {len(schedule.segments)} segments, "
          f"{schedule.total_ms} ms at {schedule.frequency_hz:g} Hz on {plan.n_sites} channels; "
          f"largest rendering error {err:.3g} um")
    if kind.live:
        record = None
        if args.out:
            # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
            from hardware.playback import JsonLines

            Path(args.out).mkdir(exist_ok=True)
            stamp = datetime.now(UTC).strftime("%Y%m%dT%H%M%S.%fZ")
            record = JsonLines(Path(args.out) / f"session-{stamp}.jsonl", "x")
        try:
            outcome = _live(kind, args, plan, schedule, meter, record)
        finally:
            if record is not None:
                record.close()
        if outcome is None and record is not None:
            print(f"wrote {record.path}")
    else:
        with write_dir("--out", args.out, kind="play", overwrite=args.overwrite,
                       reads=[args.plan, args.pattern]) as tmp:
            with open_device(args.device, plan, tmp) as dev:
                outcome = _play(kind, dev, args, plan, schedule, meter)
            if outcome is not None and not kind.keeps_refusal:
                raise outcome  # nothing to keep: the sim draws only what it played
            names = sorted(p.name for p in tmp.iterdir())  # before the marker is added
        for name in names:
            print(f"wrote {Path(args.out) / name}" + (" (the refusal)" if outcome else ""))
    if outcome is None:
        return 0
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from hardware.device import PlaybackInterrupted

    if isinstance(outcome, PlaybackInterrupted):
        print(outcome.report["summary"], file=sys.stderr)
        print("hapticrom play: failed: the pattern was not played in full", file=sys.stderr)
        return 1
    raise outcome


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``play`` subcommand."""
    p = subparsers.add_parser("play", help="play a pattern on a planned array (sim, log, "
                              "serial)")
    p.add_argument("plan", help="plan JSON from `hapticrom plan --out` (with its timing)")
    p.add_argument("pattern", help="pattern TOML (see examples/pattern-sweep.toml)")
    p.add_argument("--device", required=True, metavar="sim|log|serial:PORT",
                   help="sim: render the skin field; log: write the commands; serial:PORT: "
                   "drive the array (try it with `hapticrom emulate`)")
    p.add_argument("--out", metavar="DIR", help="output directory (sim, log: an existing one "
                   "is replaced only with --overwrite and only if play wrote it; serial: the "
                   "folder session records are added to)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace the output of an earlier play in --out")
    p.add_argument("--allow-edited-plan", action="store_true",
                   help="play a plan whose digest does not match (edited) or that has none; "
                   "recorded in the log")
    p.add_argument("--limits", type=Path, metavar="TOML",
                   help="user limits file ([limits] max_level, max_on_ms, max_duty, "
                   "watchdog_ms, exposure_action_m_s2); can only lower the device's and the "
                   "actuator's")
    p.add_argument("--max-level", type=_level, metavar="LEVEL",
                   help="largest drive level (multiple of the nominal voltage); default the "
                   "actuator's maximum over nominal voltage, or the device's if lower")
    p.add_argument("--max-on-ms", type=_positive_ms, metavar="MS",
                   help="longest continuous on-time per channel (default 10000, or the "
                   "device's if lower)")
    p.add_argument("--max-duty", type=_fraction, metavar="FRACTION",
                   help="largest on-time fraction of any 60 s window (default 0.5)")
    p.add_argument("--watchdog-ms", type=number_in(0.0, 60_000.0, "ms"), metavar="MS",
                   help="serial: the heartbeat deadline the host keeps (default 250, or the "
                   "device's if shorter)")
    p.add_argument("--exposure-action", type=_action, metavar="M/S2",
                   help="daily exposure action value A(8) (default 2.5, Directive "
                   "2002/44/EC)")
    p.add_argument("--exposure-file", type=Path, metavar="JSONL",
                   help="serial: today's accumulated exposure, read and appended to as it "
                   "accrues")
    p.set_defaults(func=_run)
