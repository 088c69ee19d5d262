"""Numerics shared by the solvers (installed as ``wearcheck.numerics``)."""
