"""Gyro-drift identification and IMU calibration models.

Plain numpy/scipy; model files are JSON or npz, never pickle.

Modules
-------
rbf
    Gaussian RBF network grown like MATLAB's ``newrb`` (seed 000).
grnn
    Specht's general regression network (seed 003).
calibration
    Traditional bias / scale-factor / misalignment model per sensor triad
    (seed 003 eqs 1-2), its least-squares fit and compensation.
rls
    Quadratic temperature model of a drift and its forgetting-factor RLS
    (seed 002).
tables
    CSV tables of named columns; seed 000's Tables 2 and 4 (packaged data).
cli
    ``sarins identify train|predict`` (``register(subparsers)``, ``run(args)``).
modelfile
    Reading and writing plain-data model files, :class:`ModelFileError`.
preprocessing
    Input checks and per-column standardisation.
"""

from .calibration import (
    TriadCalibration,
    compensate_triad,
    cube_orientations,
    fit_triad,
    rate_test_truth,
    triad_model,
    tumble_truth,
)
from .grnn import GRNN, GRNNSettings
from .modelfile import ModelFileError
from .rbf import RBFNetwork, RBFSettings
from .rls import (
    MONTH,
    ForgettingRLS,
    QuadraticFit,
    RLSSettings,
    fit_quadratic_temperature_model,
    forgetting_least_squares,
    weighted_least_squares,
)
from .tables import (
    SEED000_SITE_LAT_DEG,
    TableError,
    read_table,
    axial_rbf_table2_hot,
    axial_rbf_table4_cold,
    write_table,
)

__all__ = [
    "TriadCalibration",
    "compensate_triad",
    "cube_orientations",
    "fit_triad",
    "rate_test_truth",
    "triad_model",
    "tumble_truth",
    "GRNN",
    "GRNNSettings",
    "ModelFileError",
    "RBFNetwork",
    "RBFSettings",
    "MONTH",
    "ForgettingRLS",
    "QuadraticFit",
    "RLSSettings",
    "fit_quadratic_temperature_model",
    "forgetting_least_squares",
    "weighted_least_squares",
    "SEED000_SITE_LAT_DEG",
    "TableError",
    "read_table",
    "axial_rbf_table2_hot",
    "axial_rbf_table4_cold",
    "write_table",
]
