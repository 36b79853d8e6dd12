"""Benchmarking: run trackers (ours and OpenCV's) on sequences, score them (OPE and VOT-style),
and write tables, JSON and plots."""
