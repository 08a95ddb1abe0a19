"""Data bundled with handsim: only files the package may redistribute (with their notices).

* ``tzionas_ijcv16/`` — the MIT-licensed Tzionas et al. (IJCV 2016) sample: the right hand and cube of
  sequence 20 and the pipe of sequence 17, with ``LICENSE`` and ``README.md``.
* ``mano/`` — the MANO right hand's mean-shape rest joints (derived from MANO; see its ``NOTICE``).
* ``coacd_cache/`` — CoACD hulls of the catalogue's concave objects (made by handsim).
"""

from pathlib import Path

ASSETS_DIR = Path(__file__).resolve().parent
TZIONAS_DIR = ASSETS_DIR / "tzionas_ijcv16"
"""The bundled Tzionas sample, laid out like the dataset (``Models/NN``, ``Configs/NN``)."""
MANO_DIR = ASSETS_DIR / "mano"
"""The MANO mean-shape joint table and its notice."""
