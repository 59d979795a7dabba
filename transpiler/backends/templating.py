"""The one jinja2 set-up of the back ends: strict, no autoescaping, block tags leave no blank lines.

Every writer (ST, the TwinCAT project files, the output README) loads its own folder of templates/ through it, so
all of them format with the same whitespace rules. The compiled templates are kept in the per-user cache.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Mapping
from types import MappingProxyType

import jinja2
from jinja2.bccache import Bucket

from transpiler.resources import cache_dir, data_dir

TEMPLATE_CACHE_FOLDER = "templates"
"""Folder of the per-user cache where jinja keeps the compiled templates."""


class _CompiledTemplates(jinja2.FileSystemBytecodeCache):
    """jinja's cache of compiled templates in a folder: jinja uses a file only when it was written for the
    template's current source by the same Python version, and compiles the template again otherwise. A file that
    cannot be read (damaged, say) or written costs only that compile."""

    def load_bytecode(self, bucket: Bucket) -> None:
        try:
            super().load_bytecode(bucket)
        except Exception:       # noqa: BLE001 - any damage of the file: compile the template as without a cache
            bucket.reset()

    def dump_bytecode(self, bucket: Bucket) -> None:
        try:
            super().dump_bytecode(bucket)
        except OSError:
            pass


# The options every environment is made with. They shape the compiled code, and jinja's cache files are keyed by the
# template's source and the Python version only, so the cache keeps one folder per set of options and jinja version.
_OPTIONS = MappingProxyType(dict(
    undefined=jinja2.StrictUndefined,
    autoescape=False,
    trim_blocks=True,
    lstrip_blocks=True,
    keep_trailing_newline=True,
    # (a template included once per POU would otherwise be checked on disk for changes at every include)
    auto_reload=False,
))


def _options_folder(options: Mapping[str, object]) -> str:
    """The cache folder's name for templates compiled with `options` by this jinja version."""
    described = repr(sorted((key, getattr(value, "__qualname__", value)) for key, value in options.items()))
    return f"jinja{jinja2.__version__}-{hashlib.sha256(described.encode()).hexdigest()[:16]}"


def template_cache(options: Mapping[str, object] = _OPTIONS) -> jinja2.BytecodeCache | None:
    """The cache of templates compiled with `options`, in the per-user cache folder; None when the folder cannot be
    made."""
    try:
        folder = cache_dir() / TEMPLATE_CACHE_FOLDER / _options_folder(options)
        folder.mkdir(parents=True, exist_ok=True)
    except (OSError, RuntimeError):       # (RuntimeError: Path.home() without a home directory)
        return None
    return _CompiledTemplates(str(folder))


def template_environment(folder: str, filters: Mapping[str, Callable]) -> jinja2.Environment:
    """An environment that loads templates/<folder> (installed copy first, else the checkout's)."""
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(data_dir("templates") / folder)),
        # (compiling the templates of project.st costs about 10 ms in every process; loading them, about 1)
        bytecode_cache=template_cache(),
        **_OPTIONS,
    )
    env.filters.update(filters)
    return env
