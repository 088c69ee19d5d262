"""The application layer: run directories, the MDR-vs-FEM comparison, studies,
exports and the ``wearcheck`` command line. The numerics live in ``mdr`` and
``fem``; this package only orchestrates, measures and draws.
"""
