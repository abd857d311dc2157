"""The mechanical model: the blank's hexahedral mesh, its material, the solid, the contact
law and the forming problem that solves them together with the rigid tools (its state a
FormingState), and the increment policy with the settings of the increment control and
the Newton loop.

Example::

    from ddpy.model import FormingProblem, HexMesh, Material, RigidTool, Solid, Swift
"""

from ddpy.model.control import (
    FormingTuning,
    IncrementController,
    IncrementLimits,
    IncrementTuning,
    NewtonSettings,
)
from ddpy.model.forming import (
    FormingError,
    FormingProblem,
    FormingResult,
    FormingState,
    IncrementRecord,
    RigidTool,
)
from ddpy.model.forming_quantities import FieldFrame
from ddpy.model.material import HardeningTable, Hill48, Material, Swift, Voce
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid
from ddpy.model.static import StaticProblem

__all__ = ["FieldFrame", "FormingError", "FormingProblem", "FormingResult", "FormingState",
           "FormingTuning", "HardeningTable", "Hill48", "HexMesh", "IncrementController",
           "IncrementLimits", "IncrementRecord", "IncrementTuning", "Material",
           "NewtonSettings", "RigidTool", "Solid", "StaticProblem", "Swift", "Voce"]
