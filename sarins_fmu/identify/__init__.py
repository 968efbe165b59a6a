"""Gyro-drift identification and IMU calibration models.

Plain numpy/scipy; model files are JSON or npz, never pickle.

Modules
-------
rbf
    Gaussian RBF network grown like MATLAB's ``newrb`` (seed 000).
grnn
    Specht's general regression network (seed 003).
modelfile
    Reading and writing plain-data model files, :class:`ModelFileError`.
preprocessing
    Input checks and per-column standardisation.
"""

from .grnn import GRNN, GRNNSettings
from .modelfile import ModelFileError
from .rbf import RBFNetwork, RBFSettings

__all__ = ["GRNN", "GRNNSettings", "ModelFileError", "RBFNetwork", "RBFSettings"]
