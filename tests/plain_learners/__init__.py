"""Plain-Python learners the tests name as ``module:Class`` (importable by worker processes)."""
