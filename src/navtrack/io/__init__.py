"""Readers and writers at the edges of navtrack (files in, files out)."""
