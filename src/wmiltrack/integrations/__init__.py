"""Adapters for other tracking toolkits.

* :mod:`wmiltrack.integrations.got10k`: a ``got10k.trackers.Tracker`` so that the GOT-10k
  toolkit's experiments (``ExperimentOTB``, ``ExperimentGOT10k``, ...) run wmiltrack, and an
  offline ``ExperimentOTB`` over a local OTB folder.
* :mod:`wmiltrack.vot`: a TraX server for the VOT toolkit (``python -m wmiltrack.vot``).

Their third-party packages come with the ``integrations`` extra (see the README).
"""
