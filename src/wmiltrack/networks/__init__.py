"""The learned models wmiltrack runs beside its trackers, in a room of their own below the
engine (nothing here imports :mod:`wmiltrack.engine`, the command line or the evaluation):

* :mod:`~wmiltrack.networks.files`: the model sets (the one registry of networks and their
  versions), their files, where they are found, fetching and checking them;
* :mod:`~wmiltrack.networks.backends`: the runtimes (onnxruntime, OpenCV's dnn) behind one
  interface;
* :mod:`~wmiltrack.networks.siamese`: what a Siamese tracker network is to the engine
  (:class:`~wmiltrack.networks.siamese.SiameseStep`) and the crops they share;
* :mod:`~wmiltrack.networks.nanotrack`: NanoTrack's network and published step;
* :mod:`~wmiltrack.networks.families`: the families and
  :func:`~wmiltrack.networks.families.load_siamese`, which builds a step from a set's name.
"""
