"""Tzionas/Ballan hand and object files (.SKEL, .LIMITS, .MOTION, .OFF, .SKIN, .VOI, Configs).

One module per format: :mod:`~handsim.io.tzionas.skel` (.SKEL), :mod:`~handsim.io.tzionas.skeleton` (the
skeleton with its .LIMITS and rest pose), :mod:`~handsim.io.tzionas.motion_file`,
:mod:`~handsim.io.tzionas.motion_recording` and :mod:`~handsim.io.tzionas.motion` (.MOTION),
:mod:`~handsim.io.tzionas.surface` (.OFF, .SKIN, .VOI), :mod:`~handsim.io.tzionas.objects` (object models),
:mod:`~handsim.io.tzionas.configs` (a sequence's Configs folder) and :mod:`~handsim.io.tzionas.sequence` (a
hand with its sequence's object tracks).
"""
