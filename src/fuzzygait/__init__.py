"""fuzzygait: gait analysis that says how far to trust its numbers.

Sub-packages mirror the architecture:

* :mod:`fuzzygait.io` -- C3D read/write, subject parameters
* :mod:`fuzzygait.mocap` -- gap filling, filtering, events, gait cycles
* :mod:`fuzzygait.kinematics` -- Conventional Gait Model segments and joint angles
* :mod:`fuzzygait.uncertainty` -- fuzzy numbers and the Graph Follower algorithm
* :mod:`fuzzygait.markererror` -- fuzzy marker-error model on joint angles
* :mod:`fuzzygait.mechanics` -- leg + prosthesis simulator
* :mod:`fuzzygait.viz` -- Rerun recordings, figures, reports
* :mod:`fuzzygait.synthetic` -- deterministic synthetic trials with known angles
"""

from fuzzygait.core.errors import C3DError, FuzzyGaitError, MarkerError, ParameterError

__version__ = "0.1.0"

__all__ = ["C3DError", "FuzzyGaitError", "MarkerError", "ParameterError", "__version__"]
