"""``python -m mechgen`` is the ``mechgen`` command."""
import sys

from mechgen.cli import console

sys.exit(console())
