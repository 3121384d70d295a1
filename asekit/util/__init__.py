"""Utilities: argument validation, the BLAS thread limit, the checksummed cache, data paths
and the plotting style."""
