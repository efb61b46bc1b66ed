"""The subcommands of ``hapticrom``, one module each.

Pattern (every module follows it, so adding a command is adding a module and a name below):

* ``register(subparsers) -> None`` adds the sub-parser, its arguments and
  ``set_defaults(func=run)``;
* ``run(args: argparse.Namespace) -> int`` calls the library and prints; it returns an exit
  code (0 ok, 1 failed) and lets library errors propagate: :func:`hapticrom.cli.main` maps
  ``FieldError``/``ValueError``/``OSError`` to 2 and ``KeyboardInterrupt`` to 130;
* heavy modules (the solver, pyarrow, onnxruntime, torch) are imported inside ``run`` so that
  ``hapticrom --help`` and light commands start fast;
* outputs are written through :func:`hapticrom.outputs.atomic_path`.
"""

#: Module names of the subcommands, in the order ``hapticrom --help`` lists them.
COMMANDS: tuple[str, ...] = ("simulate", "reproduce", "generate", "dataset", "ingest", "train",
                             "refine", "predict", "models", "calibrate", "plan", "design", "play",
                             "emulate", "bench", "explore")
