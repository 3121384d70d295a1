"""The case layer: a declarative model of one flat all-movable surface or plate wing (a TOML
case file, :mod:`asekit.case.schema`) and the pipeline that analyses it
(:mod:`asekit.case.pipeline`): modes -> GAF database -> flutter -> (actuator) ASE loop."""

from asekit.case.imported import ImportedModel
from asekit.case.schema import (
                                ActuatorSpec,
                                AeroSpec,
                                Case,
                                CaseError,
                                DampingSpec,
                                FlightSpec,
                                FlutterIndexSpec,
                                FlutterSpec,
                                ModesSpec,
                                PanelSpec,
                                PointMass,
                                SolverError,
                                SupportSpec,
                                case_from_dict,
                                load_case,
)

__all__ = ["ActuatorSpec", "AeroSpec", "Case", "CaseError", "DampingSpec", "FlightSpec",
           "FlutterIndexSpec", "FlutterSpec", "ImportedModel", "ModesSpec", "PanelSpec",
           "PointMass", "SolverError", "SupportSpec",
           "case_from_dict", "load_case"]
