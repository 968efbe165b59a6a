"""Gyro-drift identification and IMU calibration models.

Plain numpy/scipy; model files are JSON or npz, never pickle.

Modules
-------
rbf
    Gaussian RBF network grown like MATLAB's ``newrb`` (seed 000).
modelfile
    Reading and writing plain-data model files, :class:`ModelFileError`.
preprocessing
    Input checks and per-column standardisation.
"""

from .modelfile import ModelFileError
from .rbf import RBFNetwork, RBFSettings

__all__ = ["ModelFileError", "RBFNetwork", "RBFSettings"]
