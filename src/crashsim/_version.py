"""The package version (one place; :data:`crashsim.__version__` and the command line read it)."""

__version__ = "0.1.0"
