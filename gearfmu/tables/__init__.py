"""Mesh tables: the format, the precompute, CSV import, synthetic shapes."""
