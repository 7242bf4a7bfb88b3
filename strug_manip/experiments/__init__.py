"""Experiments: one episode (``episode``), Table I runs (``bench``), tables (``table``)."""
