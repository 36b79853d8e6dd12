"""Sequences and box files: OTB-layout folders, image folders, videos, and generated sequences."""
