"""mechgen's version, in a module of its own so that any module can read it without importing the
package's ``__init__`` (the code generators stamp it into generated files)."""

__version__ = "0.1.0"
