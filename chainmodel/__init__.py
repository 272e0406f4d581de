"""ChainDrive: a roller chain drive model for system simulation.

Quick tour::

    import chainmodel
    drive = chainmodel.preset("C1")
    drive = chainmodel.Drive(n_driver=12, n_driven=18, pitch=0.0254, span_pitches=11,
                             pitch_fraction=0.4302)
    drive = chainmodel.Drive.from_links(n_driver=25, n_driven=17, pitch=0.015875, links=46)
    from chainmodel import kinematics
    k = kinematics.exact(drive, theta4, omega4=10.47)
    result = chainmodel.simulate("xu2010", fidelity="kinematic", duration=0.5)
    result.time, result["driven.speed"]
"""

from . import kinematics
from .geometry import Drive, Sprocket
from .models import Inputs, SimulationDiverged
from .parameters import PARAMETERS
from .presets import preset, preset_names
from .scene import Scene, load_scene
from .simulation import Result, simulate

from ._version import __version__


def sweep(study, out=None, **kw):
    """Run a design study (a study .toml, a dict or a Study) serially or on Dask and write its
    tables and figures: :func:`chainmodel.analysis.sweep.sweep` (imported on first use)."""
    from .analysis.sweep import sweep as _sweep
    return _sweep(study, out, **kw)

__all__ = ["Drive", "Sprocket", "kinematics", "preset", "preset_names", "simulate", "Result",
           "Scene", "load_scene", "Inputs", "SimulationDiverged", "PARAMETERS", "__version__",
           "sweep"]
