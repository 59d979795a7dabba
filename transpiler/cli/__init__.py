"""The `hh2iec` command line, the top floor: it parses arguments, calls the library and prints.

Nothing in the library imports this package. Each subcommand lives in its own module and is
registered explicitly in `app.build_parser`; exit codes are 0 success, 1 the check failed,
2 bad input.
"""

from transpiler.cli.app import entry, main

__all__ = ["entry", "main"]
