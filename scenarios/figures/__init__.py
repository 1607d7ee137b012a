"""Matplotlib figures of results and route drawings. Imports only ``sim``."""
