"""Array layout planning on the run-time surrogate (numpy + onnxruntime; never the FE solver,
torch or scikit-learn).

    from planner import load_layout, plan_layout
    plan = plan_layout(load_layout("examples/forearm-layout.toml"))
"""

from planner.crosstalk import UnitField, crosstalk_matrix, leakage_ratio, site_positions
from planner.drive import DriveSolution, drive_levels
from planner.layout import LayoutError, LayoutRequest, layout_from_dict, load_layout
from planner.optimise import DesignResult, Plan, plan_layout
from planner.report import plan_as_record, plan_to_dict, write_plan_plot
from planner.threshold import VERRILLO_1966_FOREARM, ThresholdCurve
from planner.timing import Timing, TimingError, envelope_timing, plan_timing

__all__ = [
           "VERRILLO_1966_FOREARM",
           "DesignResult",
           "DriveSolution",
           "LayoutError",
           "LayoutRequest",
           "Plan",
           "ThresholdCurve",
           "Timing",
           "TimingError",
           "UnitField",
           "crosstalk_matrix",
           "drive_levels",
           "envelope_timing",
           "layout_from_dict",
           "leakage_ratio",
           "load_layout",
           "plan_as_record",
           "plan_layout",
           "plan_timing",
           "plan_to_dict",
           "site_positions",
           "write_plan_plot",
]
