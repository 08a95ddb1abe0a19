"""Loading pickles (``.pkl``, ``allow_pickle`` ``.npy``) without executing anything they name.

A pickle is a program: every ``GLOBAL`` it names is imported and may be called, so ``pickle.load`` on a
downloaded file can run arbitrary code. handsim reads such files (ARCTIC's ``*.mano.npy`` is a pickled
dict; MANO's ``MANO_RIGHT.pkl`` is a Python 2 pickle) with a restricted :class:`pickle.Unpickler` whose
``find_class`` resolves only a fixed table of names:

* numpy array reconstruction: ``numpy.core.multiarray._reconstruct`` (and ``numpy._core…``),
  ``numpy.ndarray``, ``numpy.dtype``, ``numpy.core.multiarray.scalar``, ``numpy.core.numeric._frombuffer``;
* plain containers: ``set``, ``frozenset``, ``complex``, ``collections.OrderedDict``; ``_codecs.encode`` for
  latin-1 only (how protocol 0–2 pickles store bytes);
* ``copyreg._reconstructor`` only to create instances of classes the caller allows (see ``allowed``);
* whatever the caller passes in ``allowed`` (MANO's reader passes inert stand-ins for ``chumpy.ch.Ch`` and
  ``scipy.sparse`` matrices that only record their state).

Any other name raises :class:`~handsim.errors.FormatError` naming the file and the refused global; the
refused object is never imported or called.
"""

from __future__ import annotations

import _compat_pickle
import ast
import collections
import io
import math
import pickle
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from handsim.errors import FormatError
from handsim.io.text_files import open_input

try:  # numpy >= 2
    from numpy._core.multiarray import _reconstruct, scalar
    from numpy._core.numeric import _frombuffer
except ImportError:  # pragma: no cover - numpy 1.x
    from numpy.core.multiarray import _reconstruct, scalar  # type: ignore[no-redef]
    from numpy.core.numeric import _frombuffer  # type: ignore[no-redef]

NPY_MAGIC = b"\x93NUMPY"


def _latin1_encode(text: str, encoding: str = "latin1") -> bytes:
    """``_codecs.encode`` as protocol 0–2 pickles use it: latin-1 text to bytes, nothing else."""
    if encoding.replace("-", "").replace("_", "").lower() not in ("latin1", "iso88591"):
        raise pickle.UnpicklingError(f"_codecs.encode with encoding {encoding!r}; only latin-1 is allowed")
    if not isinstance(text, str):
        raise pickle.UnpicklingError("_codecs.encode of a non-string")
    return text.encode("latin1")


def _numpy_globals() -> dict[tuple[str, str], Any]:
    table: dict[tuple[str, str], Any] = {}
    for core in ("numpy.core", "numpy._core"):
        table[(f"{core}.multiarray", "_reconstruct")] = _reconstruct
        table[(f"{core}.multiarray", "scalar")] = scalar
        table[(f"{core}.numeric", "_frombuffer")] = _frombuffer
    table[("numpy", "ndarray")] = np.ndarray
    table[("numpy", "dtype")] = np.dtype
    return table


SAFE_GLOBALS: dict[tuple[str, str], Any] = {
    **_numpy_globals(),
    ("builtins", "set"): set,
    ("builtins", "frozenset"): frozenset,
    ("builtins", "complex"): complex,
    ("collections", "OrderedDict"): collections.OrderedDict,
    ("_codecs", "encode"): _latin1_encode,
}
"""The globals every restricted load resolves: numpy array reconstruction and plain containers."""


class _Unpickler(pickle.Unpickler):
    """An unpickler that resolves only the globals in its table."""

    def __init__(self, file: io.BufferedIOBase, path: Path, table: Mapping[tuple[str, str], Any]) -> None:
        super().__init__(file, encoding="latin1")
        self._path = path
        self._table = table
        self._classes = tuple(v for v in table.values() if isinstance(v, type) and v not in (set, frozenset))

    def find_class(self, module: str, name: str) -> Any:
        module, name = _python3_name(module, name)
        if (module, name) in self._table:
            return self._table[(module, name)]
        if (module, name) == ("copyreg", "_reconstructor"):
            return self._reconstructor
        if (module, name) == ("builtins", "object"):
            return object  # only useful as _reconstructor's base argument
        allowed = sorted(f"{m}.{n}" for m, n in self._table)
        raise FormatError(
            self._path,
            f"the pickle refers to the global '{module}.{name}', which handsim refuses to load (it was "
            f"neither imported nor called); allowed globals: {', '.join(allowed)}",
        )

    def _reconstructor(self, cls: type, base: type, state: Any) -> Any:
        """``copyreg._reconstructor`` restricted to the stand-in classes the caller allowed."""
        if cls not in self._classes or base is not object or state is not None:
            raise pickle.UnpicklingError(f"copyreg._reconstructor for {cls!r}, which is not allowed")
        return object.__new__(cls)


def _python3_name(module: str, name: str) -> tuple[str, str]:
    """Map Python 2 names (``__builtin__.set``, ``copy_reg._reconstructor``) to their Python 3 names."""
    if (module, name) in _compat_pickle.NAME_MAPPING:
        return _compat_pickle.NAME_MAPPING[(module, name)]
    return _compat_pickle.IMPORT_MAPPING.get(module, module), name


def _unpickle(file: io.BufferedIOBase, path: Path, allowed: Mapping[tuple[str, str], Any] | None) -> Any:
    table = {**SAFE_GLOBALS, **(allowed or {})}
    try:
        return _Unpickler(file, path, table).load()
    except FormatError:
        raise
    except (pickle.UnpicklingError, EOFError, TypeError, ValueError, AttributeError, KeyError) as exc:
        raise FormatError(path, f"not a valid pickle of arrays: {type(exc).__name__}: {exc}") from None


def load_restricted_pickle(path: str | Path, allowed: Mapping[tuple[str, str], Any] | None = None) -> Any:
    """Unpickle a file, resolving only numpy array reconstruction, plain containers and ``allowed``.

    Python 2 pickles (MANO's ``.pkl``) are read with ``encoding="latin1"``, as numpy requires.

    Args:
        path: The ``.pkl`` file.
        allowed: Extra globals, ``(module, name) → object`` to return for it (e.g. an inert stand-in
            class). Classes listed here may also be created through ``copyreg._reconstructor``.

    Returns:
        The unpickled object.

    Raises:
        InputFileError: The file does not exist, is not a regular file, or is larger than
            :data:`~handsim.io.text_files.MAX_FILE_BYTES` (:func:`~handsim.io.text_files.open_input`).
        FormatError: The pickle names a global outside the allowed table (the message names the file
            and the global; nothing was executed), or it is not a valid pickle.
    """
    p = Path(path)
    with open_input(p) as (f, _):
        return _unpickle(f, p, allowed)


def loads_restricted_pickle(
    data: bytes, source: str | Path, allowed: Mapping[tuple[str, str], Any] | None = None
) -> Any:
    """Unpickle bytes read from ``source`` as :func:`load_restricted_pickle` unpickles a file.

    Raises:
        FormatError: As :func:`load_restricted_pickle` (naming ``source``).
    """
    return _unpickle(io.BytesIO(data), Path(source), allowed)


def _check_npy_size(p: Path, shape: tuple[int, ...], dtype: np.dtype, count: int, available: int) -> None:
    """Refuse a ``.npy`` header whose shape × dtype needs more bytes than follow it in the file.

    Checked before the array is allocated: a header may claim any shape (10¹² rows would be terabytes),
    and only the file's size tells whether the data is there.
    """
    needed = count * dtype.itemsize
    if needed > available:
        raise FormatError(
            p,
            f"the header declares an array of shape {shape} and dtype {dtype} ({needed} bytes of data), "
            f"but the file holds {available} bytes after its header: a truncated or corrupted file",
        )


def load_npy(path: str | Path, allowed: Mapping[tuple[str, str], Any] | None = None) -> np.ndarray:
    """Read a ``.npy`` file; an object array (``allow_pickle``) is unpickled with the restricted unpickler.

    Args:
        path: The ``.npy`` file.
        allowed: Extra globals for an object array's pickle, as in :func:`load_restricted_pickle`.

    Returns:
        The array. A pickled dict saved with ``np.save`` comes back as a 0-d object array (use
        ``.item()``).

    Raises:
        InputFileError: The file does not exist, is not a regular file, or is larger than
            :data:`~handsim.io.text_files.MAX_FILE_BYTES` (:func:`~handsim.io.text_files.open_input`).
        FormatError: Not a ``.npy`` file, a malformed header, a header whose shape and dtype need more
            bytes than the file holds (refused before anything is allocated), a refused global, or a
            pickle that is not the array the header describes.
    """
    p = Path(path)
    with open_input(p) as (f, size):
        if f.read(6) != NPY_MAGIC:
            raise FormatError(p, "not a .npy file (no \\x93NUMPY magic)")
        version = f.read(2)
        if len(version) != 2 or version[0] not in (1, 2, 3):
            raise FormatError(p, f"unsupported .npy format version {tuple(version)}")
        size_bytes = 2 if version[0] == 1 else 4
        header_len = int.from_bytes(f.read(size_bytes), "little")
        text = f.read(header_len).decode("utf8" if version[0] == 3 else "latin1")
        try:
            header = ast.literal_eval(text)
            dtype = np.lib.format.descr_to_dtype(header["descr"])
            shape = tuple(header["shape"])
            fortran = bool(header["fortran_order"])
            if not all(isinstance(n, int) and not isinstance(n, bool) and n >= 0 for n in shape):
                raise ValueError(f"shape {shape} is not a tuple of whole numbers ≥ 0")
        except (ValueError, SyntaxError, KeyError, TypeError, MemoryError) as exc:
            raise FormatError(p, f"malformed .npy header {text.strip()!r}: {exc}") from None
        if not dtype.hasobject:
            count = math.prod(shape)
            _check_npy_size(p, shape, dtype, count, size - f.tell())
            data = np.fromfile(f, dtype=dtype, count=count)
            if data.size != count:
                raise FormatError(p, f"truncated .npy data: expected {count} values, found {data.size}")
            return data.reshape(shape, order="F" if fortran else "C")
        array = _unpickle(f, p, allowed)
    if not isinstance(array, np.ndarray) or array.shape != shape:
        got = array.shape if isinstance(array, np.ndarray) else type(array).__name__
        raise FormatError(
            p, f"the pickled payload is {got}, not the array of shape {shape} the header declares"
        )
    return array
