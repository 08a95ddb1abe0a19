"""Dataset runs: discovery of trials, one record per trial, execution in-process, on local cores or on Ray.

* :mod:`handsim.runner.discover` — a dataset folder as trials (:class:`~handsim.runner.discover.TrialEntry`),
  companion and unknown files; the layouts it knows are in :mod:`handsim.runner.layouts`.
* :mod:`handsim.runner.worker` — one trial from files to record (:func:`~handsim.runner.worker.run_trial`).
* :mod:`handsim.runner.execute` — :func:`~handsim.runner.execute.run_dataset`: every trial, resumable.
* :mod:`handsim.runner.records` — ``OUT/records.jsonl`` and ``OUT/run.json`` (schema: ``docs/records.md``).

Importing this package imports neither MuJoCo nor the submodules.
"""
