"""ARCTIC sequences and object templates, and the MANO model files they are read with.

:mod:`~handsim.io.arctic.sequence` (``<seq>.mano.npy`` with ``<seq>.object.npy``; the hands read by
:mod:`~handsim.io.arctic.mano_file`, every field checked by :mod:`~handsim.io.arctic.motion_checks`),
:mod:`~handsim.io.arctic.templates` (object template folders), :mod:`~handsim.io.arctic.mano` and
:mod:`~handsim.io.arctic.mano_pickle` (the user's ``MANO_*.pkl``), :mod:`~handsim.io.arctic.mano_pose`
(MANO poses as joint angles).
"""
