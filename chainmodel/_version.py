"""The package version, in a module of its own (chainmodel.analysis reads it without importing
the package's top level, which imports the analysis tools' entry points)."""

__version__ = "0.1.0"
