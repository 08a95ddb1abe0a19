"""Unpickling a MANO model file without chumpy: inert stand-ins for the objects a MANO ``.pkl`` names.

MPI's ``MANO_*.pkl`` are Python 2 pickles of a dict whose arrays are ``chumpy.ch.Ch`` objects and
``scipy.sparse`` csc/csr matrices. :data:`MANO_PICKLE_GLOBALS` maps each of those globals to a stand-in
that only keeps arrays (chumpy is never imported); :func:`~handsim.io.safe_pickle.load_restricted_pickle`
refuses every other global, and :func:`mano_array` turns an unpickled entry into a plain numpy array.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from handsim.errors import FormatError


class ChumpyArray:
    """Inert stand-in for ``chumpy.ch.Ch`` while unpickling: keeps only the value array ``x``."""

    x: Any = None

    def __setstate__(self, state: Any) -> None:
        if isinstance(state, tuple) and len(state) == 2:  # (dict state, slot state)
            state = state[0]
        self.x = state.get("x") if isinstance(state, dict) else None


class SparseMatrixStub:
    """Inert stand-in for a pickled ``scipy.sparse`` csc/csr matrix: keeps its arrays, rebuilt densely."""

    layout = "csc"
    state: Any = None

    def __setstate__(self, state: Any) -> None:
        self.state = state

    def to_dense(self) -> np.ndarray:
        """The matrix as a dense float array, rebuilt by :mod:`scipy.sparse` from the pickled arrays.

        The arrays are fully checked (``check_format(full_check=True)``: index pointers, index range)
        before scipy's native code densifies them.

        Raises:
            ValueError: The state lacks ``data``/``indices``/``indptr``/shape or they are inconsistent.
        """
        s = self.state if isinstance(self.state, dict) else {}
        shape = s.get("_shape", s.get("shape"))
        data, indices, indptr = (np.asarray(s.get(k)) for k in ("data", "indices", "indptr"))
        if shape is None or data.ndim != 1 or indices.shape != data.shape or indptr.ndim != 1:
            raise ValueError(f"sparse matrix state has keys {sorted(s)}; need data, indices, indptr, _shape")
        if indices.dtype.kind not in "iu" or indptr.dtype.kind not in "iu":
            raise ValueError(
                f"sparse indices and indptr must be integers, got {indices.dtype} and {indptr.dtype}"
            )
        nrows, ncols = (int(n) for n in shape)
        # lazy: only a MANO .pkl needs scipy.sparse; the ARCTIC readers beside this module are light
        import scipy.sparse

        build = scipy.sparse.csc_array if self.layout == "csc" else scipy.sparse.csr_array
        try:
            matrix = build((data.astype(float), indices, indptr), shape=(nrows, ncols))
            matrix.check_format(full_check=True)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"inconsistent {self.layout} arrays for shape {(nrows, ncols)}: {exc}") from None
        return matrix.toarray()


class CscStub(SparseMatrixStub):
    """Stand-in for ``scipy.sparse.csc_matrix``."""

    layout = "csc"


class CsrStub(SparseMatrixStub):
    """Stand-in for ``scipy.sparse.csr_matrix``."""

    layout = "csr"


MANO_PICKLE_GLOBALS: dict[tuple[str, str], type] = {
    ("chumpy.ch", "Ch"): ChumpyArray,
    ("chumpy", "Ch"): ChumpyArray,
    **{(m, "csc_matrix"): CscStub for m in ("scipy.sparse.csc", "scipy.sparse._csc")},
    **{(m, "csr_matrix"): CsrStub for m in ("scipy.sparse.csr", "scipy.sparse._csr")},
}
"""Globals a MANO pkl may name beyond numpy, each mapped to an inert stand-in (chumpy is never imported)."""


def mano_array(path: Path, key: str, value: Any) -> np.ndarray:
    """An unpickled MANO entry as a numeric numpy array: a stand-in's array, or the array itself.

    Args:
        path: The file, for messages.
        key: The entry's name, for messages.
        value: The unpickled value (a stand-in of :data:`MANO_PICKLE_GLOBALS` or a numpy array).

    Returns:
        The array (a sparse matrix densified).

    Raises:
        FormatError: A sparse matrix with inconsistent arrays, or a value that is no numeric array (the
            message names the file and the entry).
    """
    if isinstance(value, ChumpyArray):
        value = value.x
    elif isinstance(value, SparseMatrixStub):
        try:
            value = value.to_dense()
        except ValueError as exc:
            raise FormatError(path, str(exc), field=key) from None
    if not isinstance(value, np.ndarray) or value.dtype.kind not in "biuf":
        raise FormatError(path, f"expected a numeric array, got {type(value).__name__}", field=key)
    return value
