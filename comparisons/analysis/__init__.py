"""Analysis of results: pure functions from arrays to numbers (metrics against a
reference solver, edge peaks, convergence orders)."""
