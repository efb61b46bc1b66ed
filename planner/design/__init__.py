"""The unit designer (``hapticrom design``): the unit that lets the densest array on a site.

One concept per module: :mod:`~planner.design.request` (the request file),
:mod:`~planner.design.catalogue` (the silicones and the model inputs of a set of rings),
:mod:`~planner.design.prototypes` (reference units read from scene files),
:mod:`~planner.design.space` (the searched space as a box of numbers),
:mod:`~planner.design.evaluate` (the objective: the planner's pitch, in batches),
:mod:`~planner.design.search` (the optimisers), :mod:`~planner.design.run` (the search end to
end), :mod:`~planner.design.verify` (the FE check, the solve passed in),
:mod:`~planner.design.record` (the sealed JSON record), :mod:`~planner.design.layout_file`
(the layout request for ``hapticrom plan``) and :mod:`~planner.design.figure`. Run time only:
numpy, onnxruntime, scipy and the optimisers; never the solver (docs/design.md).
"""

from planner.design.request import DesignRequest, DesignRequestError, load_design_request
from planner.design.run import DesignOutcome, design

__all__ = ["DesignOutcome", "DesignRequest", "DesignRequestError", "design",
           "load_design_request"]
