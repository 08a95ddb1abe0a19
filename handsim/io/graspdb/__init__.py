"""GraspDB14 files: CyberGlove recordings, .xmlskel skeletons, phase annotations, glove calibrations.

One module per format: :mod:`~handsim.io.graspdb.glove` (recordings, radians or raw counts, with
:mod:`~handsim.io.graspdb.rows` for their rows and :mod:`~handsim.io.graspdb.filenames` for what their
names say), :mod:`~handsim.io.graspdb.xmlskel` (skeletons), :mod:`~handsim.io.graspdb.annotations` (phase
annotations) and :mod:`~handsim.io.graspdb.calibration` (handsim's glove calibration files).
:mod:`~handsim.io.graspdb.default_skeleton` builds the parametric default hand in the .xmlskel's
conventions.
"""
