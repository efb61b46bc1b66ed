"""Subcommand modules of the ``hapticrom`` CLI: each has ``register(subparsers)``."""
