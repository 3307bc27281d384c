"""brdf_atlas: a GPLVM latent space of measured BRDFs, from Python.

Open a model written by ``brdf-atlas fit`` (or :func:`fit`), then ask it
for the material at any latent point: its blend weights, its whole MERL
table, its reflectance for direction pairs, its albedo map, where another
material lands. :mod:`brdf_atlas.mitsuba` renders the materials in
Mitsuba 3.

>>> import numpy as np, brdf_atlas as ba
>>> model = ba.Model("atlas.atlas")                       # doctest: +SKIP
>>> wi = wo = np.array([[0.0, 0.0, 1.0]])
>>> model.eval([0.3, -0.5], wi, wo)                       # doctest: +SKIP
array([[0.151..., 0.122..., 0.093...]])

Tables are float64 arrays shaped ``(3, n_theta_h, n_theta_d, n_phi_d)``
(channel, then the MERL layout), reflectance in 1/sr with NaN where
unmeasured. Directions are ``(n, 3)`` arrays, float32 or float64, in the
local frame (z is the normal). Errors are :mod:`brdf_atlas.errors`
classes carrying the command-line tool's one-line message. Every long call
releases the GIL, so threads run queries in parallel.
"""

from . import errors
from ._native import Location, Material, Model, __version__, fit, read_merl, write_merl
from .errors import Error, FileError, FormatError, InputError, NumericalError

__all__ = [
    "Model",
    "Material",
    "Location",
    "fit",
    "read_merl",
    "write_merl",
    "errors",
    "Error",
    "InputError",
    "FileError",
    "FormatError",
    "NumericalError",
    "__version__",
]
