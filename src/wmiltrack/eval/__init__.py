"""Benchmarking: run trackers (ours and OpenCV's) on sequences, score them (OPE and VOT-style),
and write tables, JSON and plots.

One pipeline in three stages: :mod:`.runner` (tasks = tracker x sequence x seed, executors,
timing), :mod:`.scoring` (the convention for frames without a box, figures per run, sequence
and tracker) and :mod:`.report` (tables, JSON, plots, box files); :mod:`.pipeline` strings them
together for ``wmiltrack eval``."""
