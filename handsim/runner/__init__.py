"""Dataset runs: discovery of trials, one record per trial, execution in-process, on local cores or on Ray.

* dataset discovery is :func:`handsim.trials.discover` (the trials of a folder, with its companion and unknown
  files; each kind of trial knows its own layout).
* :mod:`handsim.runner.worker` — one trial from files to record (:func:`~handsim.runner.worker.run_trial`).
* :mod:`handsim.runner.execute` — :func:`~handsim.runner.execute.run_dataset`: every trial, resumable.
* :mod:`handsim.runner.local_backend`, :mod:`handsim.runner.ray_backend` — where the trials run: this
  process or a pool of spawned workers; Ray tasks.
* :mod:`handsim.runner.run_summary` — what a run did, counted from its records.
* :mod:`handsim.runner.records` — ``OUT/records.jsonl`` and ``OUT/run.json`` (schema: ``docs/records.md``).
* :mod:`handsim.runner.portable` — records whose paths are relative to the dataset root, and back.
* :mod:`handsim.runner.output_lock` — one run per output at a time: a lock file naming its holder
  (``OUT/.handsim.lock``; the Minari export locks each dataset id the same way).

Importing this package imports neither MuJoCo nor the submodules.
"""
