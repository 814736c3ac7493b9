"""Matplotlib figures used by the CLI and the reports."""
