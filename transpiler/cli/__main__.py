"""`python -m transpiler.cli` runs the `hh2iec` command line."""

from transpiler.cli.app import entry

entry()
