"""The package version (one source: pyproject reads it; runs record it)."""
__version__ = "0.1.0"
