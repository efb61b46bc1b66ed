"""The reproduction of Guo et al. 2025 (Biomimetics 10:597): every study of the paper re-run on
the `fem` solver, our numbers beside theirs, and checks of why they may differ.

Entry point: :func:`reproduce` (``hapticrom reproduce``).
"""

from .study import Reproduction, reproduce

__all__ = ["Reproduction", "reproduce"]
