"""The exceptions brdf_atlas raises.

Every failure carries the one-line message the ``brdf-atlas`` command-line
tool prints for the same failure (without its ``error:`` prefix): the file
or argument, then what was expected. All derive from :class:`Error`, and
each also from the built-in exception it is a case of, so ``except
ValueError`` or ``except OSError`` catch them too.
"""

__all__ = ["Error", "InputError", "FileError", "FormatError", "NumericalError"]


class Error(Exception):
    """Any failure of brdf_atlas."""


class InputError(Error, ValueError):
    """An argument the library cannot use: a latent point of the wrong
    length or not finite, direction arrays of the wrong shape or with NaN,
    fit parameters out of range."""


class FileError(Error, OSError):
    """The operating system refused a file operation: a missing model or
    MERL file, a directory that cannot be written."""


class FormatError(Error, ValueError):
    """A file that is not what was expected: a truncated or invalid MERL
    file, a model file of another format or version, a store that does not
    match its model, a data directory without MERL files."""


class NumericalError(Error, ArithmeticError):
    """A numerical failure: a kernel matrix that is not positive definite,
    an eigen-decomposition that did not converge."""
