"""3D boundary-element solver of gross-slip Reye–Archard wear on the elastic half-space."""
