"""``hapticrom emulate --channels N``: an emulated array controller on a pseudo-terminal, for
trying the serial path without hardware.

    hapticrom emulate --channels 16            # prints the port, e.g. /dev/pts/3
    hapticrom play out/plan.json examples/pattern-sweep.toml --device serial:/dev/pts/3

The emulator (:class:`hardware.emulator.PtyEmulator`) speaks the frame protocol of
docs/protocol.md and enforces the firmware's rules: watchdog, on-time limit, level limit
(default: the ERM's rated 4.5 V / 3.3 V), refusals by NAK. The port goes to stdout alone on
its line (for scripts); what the emulator does (watchdog and on-time stops, refused frames)
goes to stderr. It runs until Ctrl-C (exit 130).
"""

from __future__ import annotations

import argparse
import sys
import time

from hapticrom.commands._args import number_in

__all__ = ["register"]

_ms = number_in(0.0, 60_000.0, "ms")
_level = number_in(0.0, 8.0)


def _run(args: argparse.Namespace) -> int:
    # lazy: a command's own library loads when it runs (`hapticrom --help`: 0.4 s)
    from hardware.emulator import (
        DEFAULT_MAX_LEVEL,
        DEFAULT_MAX_ON_S,
        DEFAULT_WATCHDOG_S,
        PtyEmulator,
    )
    from hardware.protocol import FrameError, Msg

    if not 1 <= args.channels <= 255:
        raise ValueError(f"--channels {args.channels}: allowed 1 to 255")
    watchdog_s = args.watchdog_ms / 1e3 if args.watchdog_ms else DEFAULT_WATCHDOG_S
    max_on_s = args.max_on_ms / 1e3 if args.max_on_ms else DEFAULT_MAX_ON_S
    max_level = args.max_level or DEFAULT_MAX_LEVEL
    with PtyEmulator(args.channels, watchdog_s=watchdog_s, max_on_s=max_on_s,
                     max_level=max_level) as emu:
        print(emu.port, flush=True)
        print(f"emulating {args.channels} channels on {emu.port}: watchdog {watchdog_s * 1e3:g} "
              f"ms, on-time limit {max_on_s:g} s, level limit {max_level:g}; Ctrl-C to stop",
              file=sys.stderr, flush=True)
        seen_events = seen_frames = 0
        while True:
            time.sleep(0.1)
            with emu.lock:
                events = emu.array.events[seen_events:]
                frames = emu.array.received[seen_frames:]
                seen_events += len(events)
                seen_frames += len(frames)
            stops = {}
            for e in events:
                if e.reason in ("watchdog", "on-time"):
                    stops.setdefault((round(e.t, 3), e.reason), []).append(e.channel)
            for (_, reason), channels in stops.items():
                print(f"{reason} stop: channels {', '.join(map(str, channels))}",
                      file=sys.stderr, flush=True)
            for _, item in frames:
                if isinstance(item, FrameError):
                    print(f"bad frame: {item.code.name} {item.detail}", file=sys.stderr,
                          flush=True)
                elif item.type == Msg.PLAY_SCHEDULE:
                    print("schedule received", file=sys.stderr, flush=True)


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``emulate`` subcommand."""
    p = subparsers.add_parser("emulate", help="run an emulated array on a pseudo-terminal "
                              "(prints the port for play --device serial:PORT)")
    p.add_argument("--channels", type=int, required=True, metavar="N",
                   help="number of channels (1-255)")
    p.add_argument("--watchdog-ms", type=_ms, metavar="MS",
                   help="stop every channel without a heartbeat for this long (default 250)")
    p.add_argument("--max-on-ms", type=_ms, metavar="MS",
                   help="stop a channel on for this long without a pause (default 10000)")
    p.add_argument("--max-level", type=_level, metavar="LEVEL",
                   help="refuse levels beyond this (default 1.364: the ERM's 4.5 V maximum "
                   "over its 3.3 V rated voltage)")
    p.set_defaults(func=_run)
