"""The tracking engine: parameters, feature banks, bag sampling, weak classifiers, feature
selection and the :class:`~wmiltrack.engine.tracker.Tracker` that walks one frame through them.

The pixel and feature work runs in the compiled core (:mod:`wmiltrack._core`); the modules here
orchestrate it.
"""
