"""ddpy: implicit finite elements for sheet metal forming with smooth tool surfaces.

Tools are described by Bezier patches, Nagata patches or bilinear facets
(Neto, Oliveira, Alves, Menezes 2014). The numerics live in a Fortran core
(``ddpy._core``); this package validates input and drives it.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("ddpy")
except PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0.1.0"

__all__ = ["__version__"]
