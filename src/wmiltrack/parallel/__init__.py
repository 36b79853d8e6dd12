"""Running independent jobs: here, in worker processes or on Dask
(:mod:`~wmiltrack.parallel.executors`, which ``eval`` and ``track --list`` use), and tracking a
list of clips on one of them (:mod:`~wmiltrack.parallel.batch`)."""
