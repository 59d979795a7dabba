"""The one jinja2 set-up of the back ends: strict, no autoescaping, block tags leave no blank lines.

Every writer (ST, the TwinCAT project files, the output README) loads its own folder of templates/ through it, so
all of them format with the same whitespace rules.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import jinja2

from transpiler.resources import data_dir


def template_environment(folder: str, filters: Mapping[str, Callable]) -> jinja2.Environment:
    """An environment that loads templates/<folder> (installed copy first, else the checkout's)."""
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(data_dir("templates") / folder)),
        undefined=jinja2.StrictUndefined,
        autoescape=False,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        # (a template included once per POU would otherwise be checked on disk for changes at every include)
        auto_reload=False,
    )
    env.filters.update(filters)
    return env
