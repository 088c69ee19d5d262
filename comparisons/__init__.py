"""The analysis and presentation of comparisons: ``analysis`` (pure functions
from results to numbers: metrics, edge peaks, convergence orders, verdicts,
fits) and ``present`` (figures, reports, progress bars, VTK files and
pictures). What runs the solvers and writes outputs (the registry, run
directories, output safety, studies, the command line) is the application, in
``wearcheck/``; the numerics live in the solver packages.
"""
