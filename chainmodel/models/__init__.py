"""The fidelity ladder: every level implements :class:`chainmodel.models.base.Model`."""

from .base import (ALL_OUTPUTS, CORE_OUTPUTS, EXTRA_OUTPUTS, Inputs, Model, OutputSpec,
                   SimulationDiverged)
from .kinematic import KinematicModel
from .torsional import TorsionalModel
from .modal import ModalModel
from .multibody import MultibodyModel
from . import torque_causality

__all__ = ["ALL_OUTPUTS", "CORE_OUTPUTS", "EXTRA_OUTPUTS", "Inputs", "Model", "OutputSpec",
           "SimulationDiverged", "KinematicModel", "MODEL_CLASSES", "model_class", "build_model"]

#: level -> model class; levels register here as they are implemented
MODEL_CLASSES: dict[int, type[Model]] = {0: KinematicModel}
MODEL_CLASSES[1] = TorsionalModel
MODEL_CLASSES[2] = ModalModel
MODEL_CLASSES[3] = MultibodyModel


def model_class(level: int) -> type[Model]:
    from ..parameters import FIDELITY_NAMES
    if level not in MODEL_CLASSES:
        raise ValueError(f"fidelity level {level} ({FIDELITY_NAMES[level]}) is not available in "
                         f"this version; available: "
                         + ", ".join(f"{k} ({FIDELITY_NAMES[k]})" for k in sorted(MODEL_CLASSES)))
    return MODEL_CLASSES[level]


def build_model(level: int, drive, params) -> Model:
    """The model of ``level`` for ``drive`` and ``params`` in the causality
    ``input_shaft.causality`` asks for: angle (the level's class) or torque (that model with
    the motor rotor on its input-shaft spring, :mod:`.torque_causality`)."""
    if params.get("input_shaft.causality", "angle") == "torque":
        from .torque_causality import torque_causal_model
        return torque_causal_model(level, drive, params, model_class(level))
    return model_class(level)(drive, params)
