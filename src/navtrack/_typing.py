"""Type aliases shared across navtrack.

The array aliases are spelled as :data:`numpy.typing.NDArray` defines them, without importing
:mod:`numpy.typing` (about 0.6 ms that every command would pay at start-up); ``ArrayLike`` is
numpy's for the type checker and ``Any`` at run time, where it appears only in annotations.
"""

from os import PathLike
from typing import TYPE_CHECKING, Any, TypeAlias

import numpy as np

FloatArray: TypeAlias = np.ndarray[tuple[Any, ...], np.dtype[np.float64]]
IntArray: TypeAlias = np.ndarray[tuple[Any, ...], np.dtype[np.int64]]
Int8Array: TypeAlias = np.ndarray[tuple[Any, ...], np.dtype[np.int8]]
BoolArray: TypeAlias = np.ndarray[tuple[Any, ...], np.dtype[np.bool_]]
if TYPE_CHECKING:
    from numpy.typing import ArrayLike
else:
    ArrayLike: TypeAlias = Any
StrPath: TypeAlias = str | PathLike[str]
