"""Resolves the declarations of an ST file (types, POUs, globals, configuration) and compiles it to one Python module.

Compiler is assembled from parts of one job each: compiler_base (state, name rules), declare_types, declare_vars
(variables, POUs, globals, externals), declare_config and emit_python."""

from __future__ import annotations

import functools
import math

from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec.declare_config import ConfigDeclarer
from transpiler.exec.stexec.declare_types import TypeDeclarer
from transpiler.exec.stexec.declare_vars import VarDeclarer
from transpiler.exec.stexec.emit_python import PythonEmitter
from transpiler.exec.stexec.errors import StError
from transpiler.exec.stexec.model import CompiledProject, PouInfo, TaskInfo
from transpiler.exec.stexec.parser import parse
from transpiler.exec.stexec.prelude import prelude_text
from transpiler.exec.stexec.pysource import PySource
from transpiler.exec.stexec.schema import TextMutation, plan

PRELUDE_FILE = "<iec-standard-library>"


@functools.lru_cache(maxsize=1)
def _prelude() -> n.SourceFile:
    return parse(prelude_text(), PRELUDE_FILE)


class Compiler(ConfigDeclarer, VarDeclarer, TypeDeclarer, PythonEmitter):
    """Parses, declares, checks and emits one ST file."""

    def run(self, text: str, mutations: tuple[TextMutation, ...] = (), impure: tuple[str, ...] = ()
            ) -> CompiledProject:
        user = parse(text, self.filename)
        if mutations:
            self.ctx.schema = plan(user, text, mutations, impure)
        elements = [(el, True) for el in _prelude().elements] + [(el, False) for el in user.elements]
        pous: list[PouInfo] = []
        configs: list[tuple[n.Configuration, int]] = []
        for ordinal, (el, is_prelude) in enumerate(elements):
            if isinstance(el, n.TypeBlock):
                for decl in el.decls:
                    self.declare_type(decl, ordinal)
            elif isinstance(el, n.Pou):
                info = self.declare_pou(el, ordinal, is_prelude)
                if info is not None:
                    pous.append(info)
            elif isinstance(el, n.GlobalBlock):
                self.declare_globals(el.block, ordinal)
            elif isinstance(el, n.Configuration):
                configs.append((el, ordinal))
        for cfg, ordinal in configs[:1]:
            self.declare_configuration(cfg, ordinal)
        for cfg, _ in configs[1:]:
            self.error(cfg.span, "only one CONFIGURATION per file is supported")
        for info in pous:
            self.resolve_externals(info)
        src = PySource()
        self.emit_structs(src)
        for info in pous:
            self.emit_pou(src, info)
        self.emit_globals(src)
        if self.diags.has_errors():
            raise StError(self.diags.errors)
        source = "\n".join(src.lines) + "\n"
        try:
            code = compile(source, f"<stexec:{self.filename}>", "exec")
        except (SyntaxError, RecursionError, MemoryError) as exc:
            span = None
            lineno = getattr(exc, "lineno", None)
            if lineno and 0 < lineno <= len(src.spans):
                span = src.spans[lineno - 1]
            self.error(span, f"statement too complex for the built-in executor ({type(exc).__name__}: {exc})")
            raise StError(self.diags.errors) from None
        return CompiledProject(
            filename=self.filename, code=code, source=source, line_spans=[None] + src.spans,
            pous=self.ctx.pous, globals=self.ctx.globals,
            locations={a: (t, attr) for a, (t, attr, _s) in self.locations.items()},
            programs=self.programs, tasks=self.tasks, has_configuration=self.has_configuration,
            loop_limit=self.ctx.loop_limit,
            unswitched=frozenset(self.ctx.schema.unswitched) if self.ctx.schema is not None else frozenset())


def compile_st(text: str, filename: str, loop_limit: int, mutations: tuple[TextMutation, ...] = (),
               impure: tuple[str, ...] = ()) -> CompiledProject:
    return Compiler(filename, loop_limit).run(text, mutations, impure)


def base_tick(tasks: list[TaskInfo]) -> int:
    tick = 0
    for t in tasks:
        tick = math.gcd(tick, t.interval_ms)
    return tick or 1
