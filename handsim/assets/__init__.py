"""Data bundled with handsim: only files the package may redistribute (with their notices).

* ``tzionas_ijcv16/`` — the MIT-licensed Tzionas et al. (IJCV 2016) sample: the right hand and cube of
  sequence 20 and the pipe of sequence 17, with ``LICENSE`` and ``README.md``.
"""

from pathlib import Path

ASSETS_DIR = Path(__file__).resolve().parent
TZIONAS_DIR = ASSETS_DIR / "tzionas_ijcv16"
"""The bundled Tzionas sample, laid out like the dataset (``Models/NN``, ``Configs/NN``)."""
