"""Numerics shared by the solvers (installed as ``wearcheck.numerics``).

:mod:`numerics.stepping`: the time stepper of the wear law, which every
gross-slip solver plugs its implicit step into. :mod:`numerics.superelement`:
node-to-node contact on a condensed compliance matrix and its implicit wear
step (the FEM's, and any solver that condenses a body onto its contact nodes).
No solver package imports another; what they share lives here.
"""
