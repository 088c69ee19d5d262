"""Studies: what runs solvers and collects their results (compare, edge study,
finite-sphere sweep, refinement, sweeps) and the Dask runner they share."""
